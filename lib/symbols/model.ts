/**
 * The shapes of "tags by name": what the source parsers produce from a PLC's
 * own DB and UDT sources (the declarations, positions kept for messages),
 * what the symbol-table readers produce, and what compileSymbols() gives
 * back (every member with its standard-access address). The parsers
 * (source-parser), the layout engine (layout), the symbol-table readers
 * (symbol-files), the name matching (names) and the client integration all
 * meet here; nothing in this file does any work.
 */
import type { AreaName, DataTypeName, PlcValue } from '../types';

/** One file given to compileSymbols(): its name (for messages and to tell its kind by extension) and its content. */
export interface SymbolSource {
  /** The file name as the user knows it, e.g. `Tank.db`, `PLC tags.xlsx`; the extension selects the reader. */
  readonly name: string;
  /** Text files as a string (or UTF-8 / UTF-16 bytes with BOM); `.xlsx` as bytes. */
  readonly content: string | Uint8Array;
}

/** Where a declaration stands in its file: 1-based line and column. */
export interface SourcePosition {
  readonly file: string;
  readonly line: number;
  readonly column: number;
}

// ---------------------------------------------------------------- declarations (parser output)

/** A literal as written in a start value, kept unevaluated until its member's type is known. */
export interface Literal {
  /** The literal's text exactly as written: `12.5`, `TRUE`, `'abc'`, `T#5s`, `16#FF`, `DTL#2024-01-01-00:00:00`. */
  readonly text: string;
  readonly at: SourcePosition;
}

/** A start value: one literal, or for arrays a list with repeat factors (`3(0), 1`) as written. */
export type StartValue =
  { readonly kind: 'literal'; readonly literal: Literal } | { readonly kind: 'list'; readonly items: readonly StartValueItem[] };
export interface StartValueItem {
  /** `n(...)` repeats its value n times; 1 when written bare. */
  readonly repeat: number;
  readonly value: StartValue;
}

/** A declared type. */
export type TypeRef =
  | {
      readonly kind: 'elementary';
      readonly type: DataTypeName;
      /** STRING[n] / WSTRING[n]: n (the default 254 when no length was written); 0 for other types. */
      readonly stringLength: number;
      readonly at: SourcePosition;
    }
  | {
      readonly kind: 'array';
      /** Bounds per dimension as declared, e.g. Array[-2..2, 1..3] → [{low:-2,high:2},{low:1,high:3}]. */
      readonly dims: readonly { readonly low: number; readonly high: number }[];
      readonly element: TypeRef;
      readonly at: SourcePosition;
    }
  | { readonly kind: 'struct'; readonly members: readonly MemberDecl[]; readonly at: SourcePosition }
  /** A user type: a TIA UDT by name (`"Motor"`, written without quotes in `name`) or a STEP 7 `UDT 5` (`number` set). */
  | { readonly kind: 'named'; readonly name: string; readonly number?: number; readonly at: SourcePosition };

export interface MemberDecl {
  /** Unquoted name: `Speed`, `Speed.Set` (quoted in the source because of the dot). */
  readonly name: string;
  readonly type: TypeRef;
  /** `:= 12.5` in the declaration. */
  readonly initial?: StartValue;
  /** `{ ExternalAccessible := 'False'; S7_SetPoint := 'True' }`, names as written, values unquoted. */
  readonly attributes: Readonly<Record<string, string>>;
  /** `// …` or `(* … *)` after the declaration, trimmed; '' when none. */
  readonly comment: string;
  readonly at: SourcePosition;
}

/** `TYPE "Name" … END_TYPE` (TIA) or `TYPE UDT 5 … END_TYPE` (STEP 7). */
export interface TypeDecl {
  readonly kind: 'type';
  /** TIA name, unquoted; for `TYPE UDT 5` the text `UDT5`, with `number` 5. */
  readonly name: string;
  readonly number?: number;
  /** The block's attributes, e.g. `S7_Optimized_Access`. */
  readonly attributes: Readonly<Record<string, string>>;
  readonly body: Extract<TypeRef, { kind: 'struct' }>;
  readonly at: SourcePosition;
}

/** `DATA_BLOCK "Name" … END_DATA_BLOCK` (TIA) or `DATA_BLOCK DB 10 …` (STEP 7). */
export interface DataBlockDecl {
  readonly kind: 'db';
  /** TIA name, unquoted; for `DATA_BLOCK DB 10` the text `DB10`, with `number` 10. */
  readonly name: string;
  readonly number?: number;
  readonly attributes: Readonly<Record<string, string>>;
  /** True when `S7_Optimized_Access := 'TRUE'` (the TIA default when the attribute is absent in a TIA source is decided by the parser and documented there). */
  readonly optimized: boolean;
  /** RETAIN / NON_RETAIN written for the block, when written. */
  readonly retain?: boolean;
  /** A STRUCT, or an instance of a UDT (`"Motor"` / `UDT 5`) or of an FB (named; refused by the layout as unsupported when unknown). */
  readonly body: TypeRef;
  /** Assignments of the BEGIN section: `Motor.Speed := 12.5;` `Step[3].Temp := 1.0;` paths as written. */
  readonly startValues: readonly { readonly path: string; readonly value: StartValue; readonly at: SourcePosition }[];
  readonly at: SourcePosition;
}

export type BlockDecl = TypeDecl | DataBlockDecl;

// ---------------------------------------------------------------- symbol tables (.sdf / .asc / .seq / .xlsx / .csv)

/** One row of a symbol table export: a block's number or an I/Q/M tag's address. */
export interface SymbolTableRow {
  /** Symbol as written (unquoted): `Tank`, `Start button`. */
  readonly name: string;
  /** The address as the table writes it, normalised to our syntax: `DB1`, `UDT5`, `FB3`, `I0.0`, `MW10:INT`, `QD4:REAL`. */
  readonly address: string;
  /** The table's data type column as written (`BOOL`, `INT`, `DB1` for a DB, `UDT 5`…), '' when none. */
  readonly dataType: string;
  readonly comment: string;
  readonly at: SourcePosition;
}

// ---------------------------------------------------------------- the compiled table

/** A compiled entry: an elementary member, an array element, a whole array or a whole struct/UDT, or an I/Q/M symbol. */
export interface SymbolEntry {
  /** The name as TIA writes it: `"Tank".Motor.Speed`, `"Recipe".Step[3].Temp`, `"Motor 1".Run`, `"Start button"`. */
  readonly name: string;
  /** The IEC type in capitals: `REAL`, `STRING[20]`, `ARRAY[1..10] OF BOOL`, `STRUCT`; a user type by its own name, `"Motor"`, `UDT 5`. */
  readonly type: string;
  readonly kind: 'elementary' | 'array' | 'struct';
  /** Elementary entries: the data type (arrays of elementary types: the element's); undefined for structs and arrays of structs. */
  readonly dataType?: DataTypeName;
  /** STRING[n] / WSTRING[n]: n; 0 otherwise. */
  readonly stringLength: number;
  readonly area: AreaName;
  /** Data block number; null for I/Q/M symbols. */
  readonly db: number | null;
  /** Byte offset in the block (or area); null in a block with optimized access, whose members have no fixed offset. */
  readonly byte: number | null;
  /** 0–7 for BOOL (and a BOOL array's first bit); null otherwise, and for every member of an optimized block. */
  readonly bit: number | null;
  /** Bytes covered from `byte` (a BOOL: 1; a packed BOOL array: the bytes its bits touch). */
  readonly size: number;
  /**
   * The absolute address in our syntax, which parseAddress() reads back to
   * the same location and type: `DB1.DBD8:REAL`, `DB1.DBX4.0`,
   * `DB1.DBB20:STRING[30]`; a struct: its bytes, `DB1.DBB10:BYTE[12]`. Null
   * in a block with optimized access: such a member is read by name over
   * S7CommPlus (`s7plus://`), never by address.
   */
  readonly address: string | null;
  /** Elementary entries with a start value in the source (declaration or BEGIN section), evaluated to its JS value. */
  readonly initial?: PlcValue;
  /** Arrays and structs: the names of their direct children (members, or elements in index order). */
  readonly children?: readonly string[];
  /** The declaration's comment, '' when none. */
  readonly comment: string;
  readonly at?: SourcePosition;
  /**
   * How S7CommPlus reaches the entry: the access area of its data block
   * (for a DB, 0x8A0E0000 plus the DB number) and the LIDs from the block
   * down to the entry (one per level: member, element, member …). Undefined
   * for tables compiled from sources (they do not know the PLC's LIDs);
   * filled by a browse of the PLC (`client.browse()` over `s7plus://`) or by
   * the simulator, which gives its members their LIDs.
   */
  readonly access?: SymbolAccess;
}

/** The S7CommPlus access path of an entry (SymbolEntry.access). */
export interface SymbolAccess {
  /** The access area of the entry's block: for a data block 0x8A0E0000 + its number. */
  readonly area: number;
  /** The LIDs from the block down to the entry, outermost first. */
  readonly lids: readonly number[];
  /**
   * The SymbolCrc of the entry's path (lib/s7plus/codec/symbol-crc.ts), sent with every read and write so that the
   * PLC refuses a LID a download gave to another member; undefined where no public rule gives it (a path through a
   * multi-dimensional array): such an entry is sent with 0, unchecked by the PLC.
   */
  readonly symbolCrc?: number;
}

/** A data block of the compiled sources. */
export interface BlockSummary {
  /** As TIA writes it (unquoted): `Tank`; a STEP 7 DB without symbol: `DB10`. */
  readonly name: string;
  readonly db: number;
  /**
   * True when the block has optimized access (`S7_Optimized_Access := 'TRUE'`):
   * its members are read by name over S7CommPlus, `length` is null and its
   * entries' byte, bit and address are null. Absent on a block with standard
   * access, so that such a summary is what it was before optimized blocks
   * compiled (a test's or a flow's deep comparison of it still holds).
   */
  readonly optimized?: boolean;
  /** Bytes of the block in standard access, as the CPU's block info reports it; null for an optimized block (no fixed layout). */
  readonly length: number | null;
  readonly file: string;
  /** The UDT or FB it is an instance of, when it is one. */
  readonly instanceOf?: string;
}

/** What compileSymbols() returns. */
export interface SymbolTable {
  /** Every entry, block by block in declaration order (a struct before its members, an array before its elements). */
  readonly entries: readonly SymbolEntry[];
  readonly blocks: readonly BlockSummary[];
  /** UDT names the sources declare (for the editor's lists). */
  readonly types: readonly string[];
  /** The entry a name as a user types it stands for (see names.ts for the rules), or undefined. */
  lookup(name: string): SymbolEntry | undefined;
  /** Up to `max` (default 3) existing names closest to a name that was not found, best first. */
  suggest(name: string, max?: number): string[];
}

export interface CompileOptions {
  /** Block numbers by name, for TIA sources (which do not carry them): `{ Tank: 1, '"Motor 1"': 2 }`. */
  readonly db?: Readonly<Record<string, number>>;
}
