/**
 * Reads the DB and UDT blocks of a PLC's own sources into declarations
 * (lib/symbols/model.ts), in the two dialects the engineering tools write:
 *
 * - TIA Portal, "Generate source from blocks" (.db, .udt, .scl):
 *   `TYPE "Motor" … STRUCT … END_STRUCT; END_TYPE`,
 *   `DATA_BLOCK "Tank" { S7_Optimized_Access := 'FALSE' } … VAR … END_VAR BEGIN … END_DATA_BLOCK`
 *   (older versions: `STRUCT … END_STRUCT;` in place of the VAR sections);
 * - STEP 7 (classic) AWL sources: `TYPE UDT 1 …`, `DATA_BLOCK DB 10 …`,
 *   `DATA_BLOCK DB 11 UDT 1`, or with symbolic names (`DATA_BLOCK "Tank"`).
 *
 * The two differ in the block header only; the declarations are the same
 * grammar, and a file may mix them. FUNCTION_BLOCK, FUNCTION and
 * ORGANIZATION_BLOCK blocks of an .scl file are skipped whole: they hold
 * no data of their own (an instance DB of an FB names the FB, which the
 * layout refuses when it does not know it).
 *
 * Start values stay unevaluated (Literal) until the layout knows each
 * member's type (literals.ts evaluates them). Errors are SourceErrors at the
 * token that is wrong, in words of the PLC programmer.
 */
import { SourceError } from '../errors';
import { MAX_STRING_LENGTH, MAX_WSTRING_LENGTH } from '../address/sizes';
import type { DataTypeName } from '../types';
import { JS_TYPES } from '../values';
import { tokenize, type Token } from './lexer';
import { isSystemTypeName } from './system-types';
import type {
  BlockDecl,
  DataBlockDecl,
  Literal,
  MemberDecl,
  SourcePosition,
  StartValue,
  StartValueItem,
  SymbolSource,
  TypeDecl,
  TypeRef,
} from './model';
import { distance } from './distance';

type StructRef = Extract<TypeRef, { kind: 'struct' }>;

/** The elementary types by their IEC names (any case), and the short forms both tools accept in declarations. */
const ELEMENTARY: ReadonlyMap<string, DataTypeName> = new Map<string, DataTypeName>([
  ...(Object.keys(JS_TYPES) as DataTypeName[]).map((t) => [t, t] as const),
  ['DT', 'DATE_AND_TIME'],
  ['TOD', 'TIME_OF_DAY'],
]);

/** Types without a fixed place in a data block's standard layout that plcwire could read: refused at the member. */
const NO_LAYOUT = new Set(['VARIANT', 'ANY', 'POINTER', 'ANY_POINTER', 'REF_TO', 'BLOCK_DB', 'BLOCK_FB', 'BLOCK_FC', 'BLOCK_SDB']);

/**
 * Nesting of STRUCTs, ARRAYs and start-value lists the parser follows: far
 * beyond what the engineering tools let a block nest, far within the stack.
 */
const MAX_DEPTH = 64;

/** Keywords that end a block or start the next one: a STRUCT or BEGIN section that meets one is unterminated. */
const BLOCK_ENDS = new Set([
  'END_TYPE',
  'END_DATA_BLOCK',
  'BEGIN',
  'TYPE',
  'DATA_BLOCK',
  'FUNCTION_BLOCK',
  'FUNCTION',
  'ORGANIZATION_BLOCK',
]);

/** Keywords that open or close a section of declarations: never a member's or a type's name. */
const SECTION_WORDS = new Set(['VAR', 'END_VAR', 'STRUCT', 'END_STRUCT', 'VAR_INPUT', 'VAR_OUTPUT', 'VAR_IN_OUT', 'VAR_TEMP']);

/** Code blocks an .scl source may hold beside its data: skipped to their END keyword. */
const SKIPPED_BLOCKS: Readonly<Record<string, string>> = {
  FUNCTION_BLOCK: 'END_FUNCTION_BLOCK',
  FUNCTION: 'END_FUNCTION',
  ORGANIZATION_BLOCK: 'END_ORGANIZATION_BLOCK',
};

/** Header lines with a `:` value (`VERSION : 0.1`); kept as block attributes under their keyword. */
const HEADER_VALUES = new Set(['AUTHOR', 'FAMILY', 'NAME', 'VERSION']);
/** Header flags, kept as block attributes with the value 'TRUE'. */
const HEADER_FLAGS = new Set(['KNOW_HOW_PROTECT', 'READ_ONLY', 'UNLINKED', 'DB_SPECIFIC']);

/**
 * Every TYPE and DATA_BLOCK of a source file, in order. Throws SourceError
 * (file:line:column) on a syntax error.
 *
 * S7_Optimized_Access when the block does not write it: TIA writes the
 * attribute for every S7-1200/1500 block it generates, so it is absent only
 * in hand-written sources and in STEP 7 ones. A block with a TIA-style
 * quoted name counts as optimized, TIA's default for a new block (and what
 * importing such a source creates on an S7-1500); a `DB n` block counts as
 * standard, since STEP 7 knows no other access. A file whose headers use a
 * number anywhere (`DB 10`, `UDT 1`), or named `*.awl` (STEP 7's
 * extension for sources), is a STEP 7 source: its symbolic
 * `DATA_BLOCK "Tank"` blocks count as standard too.
 */
export function parseBlockSource(source: SymbolSource): BlockDecl[] {
  const parser = new Parser(tokenize(sourceText(source.content), source.name), source.name);
  const blocks = parser.blocks();
  const step7 = /\.awl$/i.test(source.name) || blocks.some((b) => b.number !== undefined);
  return blocks.map((b) => {
    if (b.kind !== 'db') return b;
    if (optimizedAttribute(b.attributes) !== undefined) return b;
    return { ...b, optimized: b.number === undefined && !step7 };
  });
}

/**
 * A source's text: strings as given, bytes by their BOM (UTF-8, UTF-16LE,
 * UTF-16BE). TIA writes UTF-8 with a BOM; STEP 7 writes its sources in the
 * Windows code page, so bytes without a BOM that are not UTF-8 are read as
 * Windows-1252. A leading BOM is dropped.
 */
function sourceText(content: string | Uint8Array): string {
  if (typeof content === 'string') return content.replace(/^\uFEFF/, '');
  const b = content;
  if (b[0] === 0xef && b[1] === 0xbb && b[2] === 0xbf) return new TextDecoder('utf-8').decode(b.subarray(3));
  if (b[0] === 0xff && b[1] === 0xfe) return new TextDecoder('utf-16le').decode(b.subarray(2));
  if (b[0] === 0xfe && b[1] === 0xff) return new TextDecoder('utf-16be').decode(b.subarray(2));
  try {
    return new TextDecoder('utf-8', { fatal: true }).decode(b);
  } catch {
    return new TextDecoder('windows-1252').decode(b);
  }
}

function upper(t: Token): string {
  return t.kind === 'ident' ? t.text.toUpperCase() : '';
}

/** A token as a message shows it. */
function describe(t: Token): string {
  switch (t.kind) {
    case 'eof':
      return 'the end of the file';
    case 'quoted':
      return `"${t.text}"`;
    case 'title':
      return `the title ${t.text}`;
    default:
      return t.text.length > 30 ? `${t.text.slice(0, 30)}…` : t.text;
  }
}

class Parser {
  private readonly code: Token[];
  /** The comment that follows a token on its own line (a declaration's `// …`). */
  private readonly trailing = new Map<Token, string>();
  private i = 0;
  /** STRUCT, ARRAY and start-value brackets open now; bounded so a hostile file cannot exhaust the stack. */
  private depth = 0;

  constructor(
    tokens: readonly Token[],
    private readonly file: string,
  ) {
    this.code = [];
    tokens.forEach((t, k) => {
      if (t.kind === 'comment') return;
      this.code.push(t);
      const next = tokens[k + 1];
      if (next?.kind === 'comment' && next.line === t.line) this.trailing.set(t, next.text);
    });
  }

  blocks(): BlockDecl[] {
    const out: BlockDecl[] = [];
    for (;;) {
      const t = this.peek();
      if (t.kind === 'eof') return out;
      const kw = upper(t);
      if (kw === 'TYPE') out.push(this.typeBlock());
      else if (kw === 'DATA_BLOCK') out.push(this.dataBlock());
      else if (SKIPPED_BLOCKS[kw] !== undefined) this.skipBlock(SKIPPED_BLOCKS[kw]);
      else throw this.error(t, `expected TYPE or DATA_BLOCK, found ${describe(t)}`);
    }
  }

  // ------------------------------------------------------------ blocks

  private typeBlock(): TypeDecl {
    const open = this.next();
    const { name, number } = this.blockName(open, 'UDT');
    if (this.isPunct(':')) this.next(); // IEC style `TYPE Name : STRUCT`
    const attributes = this.header();
    const structTok = this.peek();
    if (upper(structTok) !== 'STRUCT')
      throw this.error(structTok, `expected STRUCT to start the members of ${name}, found ${describe(structTok)}`);
    const body = this.struct(this.next());
    this.semicolonAfterStruct(body, `TYPE ${name}`);
    this.expectWord('END_TYPE', `END_TYPE missing for TYPE ${name} opened at ${open.line}:${open.column}`);
    return { kind: 'type', name, ...(number === undefined ? {} : { number }), attributes: attributes.values, body, at: this.pos(open) };
  }

  private dataBlock(): DataBlockDecl {
    const open = this.next();
    const { name, number } = this.blockName(open, 'DB');
    const head = this.header();
    const body = this.dbBody(name);
    const startValues: DataBlockDecl['startValues'][number][] = [];
    if (upper(this.peek()) === 'BEGIN') {
      this.next();
      for (;;) {
        const t = this.peek();
        if (upper(t) === 'END_DATA_BLOCK') break;
        if (t.kind === 'eof' || BLOCK_ENDS.has(upper(t))) {
          throw this.error(t, `END_DATA_BLOCK missing for DATA_BLOCK ${name} opened at ${open.line}:${open.column}, found ${describe(t)}`);
        }
        startValues.push(this.assignment());
      }
    }
    this.expectWord('END_DATA_BLOCK', `END_DATA_BLOCK missing for DATA_BLOCK ${name} opened at ${open.line}:${open.column}`);
    const optimized = optimizedAttribute(head.values);
    if (optimized !== undefined && !/^(TRUE|FALSE)$/i.test(optimized)) {
      throw this.error(head.optimizedAt!, `S7_Optimized_Access is '${optimized}'; it must be 'TRUE' or 'FALSE'`);
    }
    return {
      kind: 'db',
      name,
      ...(number === undefined ? {} : { number }),
      attributes: head.values,
      // Absent: decided per file in parseBlockSource.
      optimized: optimized !== undefined && optimized.toUpperCase() === 'TRUE',
      ...(head.retain === undefined ? {} : { retain: head.retain }),
      body,
      startValues,
      at: this.pos(open),
    };
  }

  /** `"Tank"`, `DB 10` / `DB10` (`UDT 5` for types), or a plain identifier. */
  private blockName(open: Token, prefix: 'DB' | 'UDT'): { name: string; number?: number } {
    const t = this.next();
    const what = open.text.toUpperCase();
    if (t.kind === 'quoted') {
      if (t.text.trim() === '') throw this.error(t, `${what} has an empty name ""`);
      return { name: t.text };
    }
    if (t.kind !== 'ident' || BLOCK_ENDS.has(upper(t)) || upper(t) === 'STRUCT') {
      throw this.error(t, `expected the name of the ${what} ("Name" or ${prefix} n), found ${describe(t)}`);
    }
    const glued = new RegExp(`^${prefix}(\\d+)$`, 'i').exec(t.text);
    if (glued) return this.numbered(prefix, glued[1]!, t);
    if (upper(t) === prefix && this.peek().kind === 'number') {
      const n = this.next();
      return this.numbered(prefix, n.text, n);
    }
    return { name: t.text };
  }

  private numbered(prefix: string, digits: string, at: Token): { name: string; number: number } {
    const n = Number(digits);
    if (!/^\d+$/.test(digits) || n < 1 || n > 65535) throw this.error(at, `${prefix} number ${digits} is not a block number (1..65535)`);
    return { name: `${prefix}${n}`, number: n };
  }

  /** The header between the name and the body: attributes, TITLE, AUTHOR/FAMILY/NAME/VERSION, RETAIN, flags. */
  private header(): { values: Record<string, string>; retain?: boolean; optimizedAt?: Token } {
    const values: Record<string, string> = {};
    let retain: boolean | undefined;
    let optimizedAt: Token | undefined;
    for (;;) {
      const t = this.peek();
      const kw = upper(t);
      if (this.isPunct('{')) {
        const found = this.attributes(values);
        optimizedAt = optimizedAttribute(found) ?? optimizedAt;
      } else if (kw === 'TITLE') {
        this.next();
        this.expectPunct('=', `expected '=' after TITLE`);
        const title = this.peek();
        if (title.kind === 'title') values.TITLE = this.next().text;
      } else if (HEADER_VALUES.has(kw) && this.isPunct(':', 1)) {
        this.next();
        this.next();
        const v = this.next();
        if (v.kind !== 'ident' && v.kind !== 'number' && v.kind !== 'string' && v.kind !== 'quoted') {
          throw this.error(v, `expected a value after ${kw} :, found ${describe(v)}`);
        }
        values[kw] = v.kind === 'string' ? unquote(v.text) : v.text;
      } else if (kw === 'RETAIN' || kw === 'NON_RETAIN') {
        this.next();
        retain = kw === 'RETAIN';
      } else if (HEADER_FLAGS.has(kw)) {
        this.next();
        values[kw] = 'TRUE';
      } else return { values, ...(retain === undefined ? {} : { retain }), ...(optimizedAt ? { optimizedAt } : {}) };
    }
  }

  /** `{ Name := 'Value'; … }` into `into`; returns where each name was written. */
  private attributes(into: Record<string, string>): Record<string, Token> {
    const open = this.next();
    const where: Record<string, Token> = {};
    for (;;) {
      const t = this.next();
      if (t.kind === 'punct' && t.text === '}') return where;
      if (t.kind === 'punct' && t.text === ';') continue;
      if (t.kind !== 'ident' && t.kind !== 'quoted') {
        throw this.error(
          t,
          `expected an attribute name or '}' to close the attributes opened at ${open.line}:${open.column}, found ${describe(t)}`,
        );
      }
      this.expectPunct(':=', `expected ':=' after the attribute ${t.text}`);
      const v = this.next();
      if (v.kind !== 'string' && v.kind !== 'ident' && v.kind !== 'number') {
        throw this.error(v, `expected a value such as 'TRUE' for the attribute ${t.text}, found ${describe(v)}`);
      }
      into[t.text] = v.kind === 'string' ? unquote(v.text) : v.text;
      where[t.text] = v;
    }
  }

  /**
   * A DB's body: its `VAR … END_VAR` sections (what TIA writes today), its
   * `STRUCT … END_STRUCT;` (older TIA versions, STEP 7, generators), or the
   * UDT, FB or system type it is an instance of: quoted (`"Motor"`), as a
   * number (`UDT 5`, `FB 3`), or a name TIA writes unquoted (`TCON_IP_v4`),
   * looked up by the layout among the sources first, then among the system
   * types it knows (lib/symbols/system-types.ts).
   */
  private dbBody(name: string): TypeRef {
    const t = this.peek();
    const kw = upper(t);
    if (kw === 'VAR') return this.varSections();
    if (kw === 'STRUCT') {
      const body = this.struct(this.next());
      this.semicolonAfterStruct(body, `DATA_BLOCK ${name}`);
      return body;
    }
    if (t.kind === 'quoted') {
      this.next();
      return { kind: 'named', name: t.text, at: this.pos(t) };
    }
    if (t.kind === 'ident' && !BLOCK_ENDS.has(kw) && !SECTION_WORDS.has(kw)) {
      const named = this.numberedType();
      if (named) return named;
      this.next();
      return { kind: 'named', name: t.text, at: this.pos(t) };
    }
    throw this.error(t, `expected VAR, STRUCT, or the UDT or FB that DATA_BLOCK ${name} is an instance of, found ${describe(t)}`);
  }

  /**
   * The `;` TIA and STEP 7 write after the END_STRUCT that closes a TYPE's or
   * a DB's STRUCT (`END_STRUCT;`, STEP 7: `END_STRUCT ;`). Both tools write
   * it in every source they generate, and a member's `END_STRUCT` needs it
   * as every declaration does, so a missing one is a damaged source.
   */
  private semicolonAfterStruct(body: StructRef, owner: string): void {
    if (this.isPunct(';')) {
      this.next();
      return;
    }
    const end = this.code[this.i - 1]!;
    throw this.error(
      end,
      `';' missing after END_STRUCT: the STRUCT of ${owner} (opened at ${body.at.line}:${body.at.column}) must end with END_STRUCT; (found ${describe(this.peek())})`,
    );
  }

  /**
   * The members of a DB in TIA's current form: one or more sections
   * `VAR` / `VAR RETAIN` / `VAR NON_RETAIN` … `END_VAR`, their members one
   * after the other as in one STRUCT (retentivity is no part of the layout).
   * `VAR CONSTANT` members hold no data in the block: they are read and left
   * out. TIA writes no `;` after END_VAR; one is accepted.
   */
  private varSections(): StructRef {
    const first = this.peek();
    const members: MemberDecl[] = [];
    const seen = new Map<string, MemberDecl>();
    while (upper(this.peek()) === 'VAR') {
      const open = this.next();
      const qualifier = upper(this.peek());
      const constant = qualifier === 'CONSTANT';
      if (constant || qualifier === 'RETAIN' || qualifier === 'NON_RETAIN' || qualifier === 'DB_SPECIFIC') this.next();
      for (;;) {
        const t = this.peek();
        const kw = upper(t);
        if (kw === 'END_VAR') {
          this.next();
          if (this.isPunct(';')) this.next();
          break;
        }
        if (t.kind === 'eof' || BLOCK_ENDS.has(kw) || SECTION_WORDS.has(kw))
          throw this.error(t, `END_VAR missing for VAR opened at ${open.line}:${open.column}, found ${describe(t)}`);
        const member = this.member(open);
        const key = member.name.toUpperCase();
        const before = seen.get(key);
        if (before)
          throw new SourceError(
            member.at,
            `${member.name} is declared twice in this block (first at ${before.at.line}:${before.at.column})`,
          );
        seen.set(key, member);
        if (!constant) members.push(member);
      }
    }
    return { kind: 'struct', members, at: this.pos(first) };
  }

  /**
   * `UDT 5` (or glued, `UDT5`) as the named type `UDT5` with its number;
   * `FB 3` / `SFB 4` as the named type `FB3` / `SFB4` WITHOUT a number,
   * since a number on a named type means a UDT (model.ts) and an instance
   * DB of FB 5 must not be laid out as UDT 5. Undefined when the next token
   * is none of these.
   */
  private numberedType(): TypeRef | undefined {
    const t = this.peek();
    const glued = /^(UDT|FB|SFB)(\d+)$/i.exec(t.text);
    const spaced = /^(UDT|FB|SFB)$/i.test(t.text) && this.peek(1).kind === 'number';
    if (t.kind !== 'ident' || (!glued && !spaced)) return undefined;
    this.next();
    const prefix = (glued ? glued[1]! : t.text).toUpperCase();
    const digits = glued ? glued[2]! : this.next().text;
    const { name, number } = this.numbered(prefix, digits, t);
    return prefix === 'UDT' ? { kind: 'named', name, number, at: this.pos(t) } : { kind: 'named', name, at: this.pos(t) };
  }

  private skipBlock(end: string): void {
    const open = this.next();
    for (;;) {
      const t = this.next();
      if (upper(t) === end) return;
      if (t.kind === 'eof') throw this.error(t, `${end} missing for ${open.text.toUpperCase()} opened at ${open.line}:${open.column}`);
    }
  }

  // ------------------------------------------------------------ declarations

  private struct(open: Token): StructRef {
    const members: MemberDecl[] = [];
    const seen = new Map<string, MemberDecl>();
    for (;;) {
      const t = this.peek();
      const kw = upper(t);
      if (kw === 'END_STRUCT') {
        this.next();
        return { kind: 'struct', members, at: this.pos(open) };
      }
      if (t.kind === 'eof' || BLOCK_ENDS.has(kw)) {
        throw this.error(t, `END_STRUCT missing for STRUCT opened at ${open.line}:${open.column}, found ${describe(t)}`);
      }
      const member = this.member(open);
      const key = member.name.toUpperCase();
      const first = seen.get(key);
      if (first)
        throw new SourceError(member.at, `${member.name} is declared twice in this STRUCT (first at ${first.at.line}:${first.at.column})`);
      seen.set(key, member);
      members.push(member);
    }
  }

  private member(open: Token): MemberDecl {
    // TIA may write RETAIN / NON_RETAIN before a member of an optimized block; retentivity is no part of the layout.
    if ((upper(this.peek()) === 'RETAIN' || upper(this.peek()) === 'NON_RETAIN') && ['ident', 'quoted'].includes(this.peek(1).kind))
      this.next();
    const first = this.i;
    const nameTok = this.next();
    if (nameTok.kind !== 'ident' && nameTok.kind !== 'quoted') {
      const kw = open.text.toUpperCase();
      throw this.error(
        nameTok,
        `expected a member name or END_${kw} (for ${kw} opened at ${open.line}:${open.column}), found ${describe(nameTok)}`,
      );
    }
    const name = nameTok.text;
    if (name.trim() === '') throw this.error(nameTok, 'a member has an empty name ""');
    const attributes: Record<string, string> = {};
    if (this.isPunct('{')) this.attributes(attributes);
    this.expectPunct(':', `expected ':' and a type after the member name ${name}`);
    const type = this.typeRef(name);
    let initial: StartValue | undefined;
    if (this.isPunct(':=')) {
      this.next();
      initial = this.startValue(name);
    }
    const semi = this.peek();
    if (!this.isPunct(';')) throw this.error(semi, `expected ';' after the declaration of ${name}, found ${describe(semi)}`);
    this.next();
    return { name, type, ...(initial ? { initial } : {}), attributes, comment: this.lineComment(first), at: this.pos(nameTok) };
  }

  /** The comment after the first line of a declaration (for a STRUCT member: after `Struct`, as TIA and STEP 7 write it). */
  private lineComment(first: number): string {
    let last = first;
    while (this.code[last + 1] && this.code[last + 1]!.line === this.code[first]!.line && last + 1 < this.i) last++;
    return this.trailing.get(this.code[last]!) ?? '';
  }

  private typeRef(member: string): TypeRef {
    return this.nested(member, () => this.typeRefAt(member));
  }

  /** Runs a nested part of a declaration, refusing nesting deeper than MAX_DEPTH. */
  private nested<T>(what: string, read: () => T): T {
    if (this.depth >= MAX_DEPTH) throw this.error(this.peek(), `${what} is nested deeper than ${MAX_DEPTH} levels`);
    this.depth++;
    try {
      return read();
    } finally {
      this.depth--;
    }
  }

  private typeRefAt(member: string): TypeRef {
    const t = this.peek();
    const kw = upper(t);
    if (t.kind === 'quoted') {
      this.next();
      if (t.text.trim() === '') throw this.error(t, `member ${member} has the empty type name ""`);
      return { kind: 'named', name: t.text, at: this.pos(t) };
    }
    if (t.kind !== 'ident') throw this.error(t, `expected the type of ${member}, found ${describe(t)}`);
    if (kw === 'STRUCT') return this.struct(this.next());
    if (kw === 'ARRAY') return this.arrayType(member);
    const numbered = this.numberedType();
    if (numbered) return numbered;
    this.next();
    const type = ELEMENTARY.get(kw);
    if (type === 'STRING' || type === 'WSTRING')
      return { kind: 'elementary', type, stringLength: this.stringLength(type, member), at: this.pos(t) };
    if (type) return { kind: 'elementary', type, stringLength: 0, at: this.pos(t) };
    if (NO_LAYOUT.has(kw)) {
      throw this.error(t, `member ${member} has the type ${t.text}, which has no fixed place in a data block plcwire could read`);
    }
    if (isSystemTypeName(kw)) return { kind: 'named', name: t.text, at: this.pos(t) };
    const limit = Math.max(1, Math.floor(kw.length / 3));
    const near = [...ELEMENTARY.keys()]
      .map((n) => ({ n, d: distance(kw, n, limit) }))
      .filter((c) => c.d <= limit)
      .sort((a, b) => a.d - b.d)[0];
    const hint = near ? ` (did you mean ${near.n}?)` : ' (a UDT is written in quotes: "Name")';
    throw this.error(t, `unknown type ${t.text} for member ${member}${hint}`);
  }

  /** `Array[1..10] of Bool`, `ARRAY [-5 .. 5, 0 .. 2 ] OF INT`. */
  private arrayType(member: string): TypeRef {
    const open = this.next();
    this.expectPunct('[', `expected '[' and the bounds after ARRAY (member ${member})`);
    const dims: { low: number; high: number }[] = [];
    for (;;) {
      const lowTok = this.peek();
      const low = this.bound(member);
      this.expectPunct('..', `expected '..' between the bounds of the ARRAY of ${member}`);
      const high = this.bound(member);
      if (low > high) throw this.error(lowTok, `the ARRAY bounds ${low}..${high} of ${member} are reversed (the low bound comes first)`);
      dims.push({ low, high });
      if (this.isPunct(']')) break;
      this.expectPunct(',', `expected ',' or ']' in the bounds of the ARRAY of ${member}`);
    }
    this.next();
    const of = this.peek();
    if (upper(of) !== 'OF') throw this.error(of, `expected OF and the element type after the bounds of ${member}, found ${describe(of)}`);
    this.next();
    return { kind: 'array', dims, element: this.typeRef(member), at: this.pos(open) };
  }

  private bound(member: string): number {
    let sign = 1;
    if (this.isPunct('-') || this.isPunct('+')) sign = this.next().text === '-' ? -1 : 1;
    const t = this.next();
    const n = Number(t.text);
    if (t.kind !== 'number' || !/^\d+$/.test(t.text) || n > 0x7fffffff) {
      throw this.error(t, `expected an integer bound in the ARRAY of ${member}, found ${describe(t)}`);
    }
    return sign * n;
  }

  /** `String[20]` / `STRING [20 ]`: the length; no bracket: 254 (TIA's and STEP 7's default). */
  private stringLength(type: 'STRING' | 'WSTRING', member: string): number {
    if (!this.isPunct('[')) return MAX_STRING_LENGTH;
    this.next();
    const t = this.next();
    const max = type === 'STRING' ? MAX_STRING_LENGTH : MAX_WSTRING_LENGTH;
    if (t.kind !== 'number' || !/^\d+$/.test(t.text)) throw this.error(t, `expected the length of ${type} ${member}, found ${describe(t)}`);
    const n = Number(t.text);
    if (n < 1 || n > max) throw this.error(t, `${type}[${t.text}] of ${member}: the length must be 1..${max}`);
    this.expectPunct(']', `expected ']' after the length of ${type} ${member}`);
    return n;
  }

  // ------------------------------------------------------------ start values

  /** `12.5`, `[1, 2, 3(0)]`, `1, 2, 3` (STEP 7 writes array values without brackets), `10(0)`. */
  private startValue(what: string): StartValue {
    return this.nested(what, () => this.startValueAt(what));
  }

  private startValueAt(what: string): StartValue {
    if (this.isPunct('[')) {
      const open = this.next();
      const items = this.items(what);
      this.expectPunct(']', `expected ']' to close the start values opened at ${open.line}:${open.column} (${what})`);
      return { kind: 'list', items };
    }
    const items = this.items(what);
    return items.length === 1 && items[0]!.repeat === 1 && items[0]!.value.kind === 'literal' && !items[0]!.grouped
      ? items[0]!.value
      : { kind: 'list', items: items.map(({ repeat, value }) => ({ repeat, value })) };
  }

  private items(what: string): (StartValueItem & { grouped?: boolean })[] {
    const items: (StartValueItem & { grouped?: boolean })[] = [];
    for (;;) {
      items.push(this.item(what));
      if (!this.isPunct(',')) return items;
      this.next();
    }
  }

  private item(what: string): StartValueItem & { grouped?: boolean } {
    const t = this.peek();
    if (t.kind === 'number' && this.isPunct('(', 1)) {
      if (!/^\d+$/.test(t.text) || Number(t.text) < 1)
        throw this.error(t, `the repeat factor ${t.text} (${what}) must be a whole number of at least 1`);
      this.next();
      const open = this.next();
      const inner = this.nested(what, () => this.items(what));
      this.expectPunct(')', `expected ')' to close the repeat opened at ${open.line}:${open.column} (${what})`);
      const value: StartValue =
        inner.length === 1 && inner[0]!.repeat === 1
          ? inner[0]!.value
          : { kind: 'list', items: inner.map(({ repeat, value: v }) => ({ repeat, value: v })) };
      return { repeat: Number(t.text), value, grouped: true };
    }
    if (this.isPunct('[')) return { repeat: 1, value: this.startValue(what), grouped: true };
    return { repeat: 1, value: { kind: 'literal', literal: this.literal(what) } };
  }

  private literal(what: string): Literal {
    const first = this.peek();
    let sign = '';
    if (this.isPunct('-') || this.isPunct('+')) {
      sign = this.next().text;
      const n = this.peek();
      if (n.kind !== 'number' && n.kind !== 'typed')
        throw this.error(n, `expected a number after ${sign} in the start value of ${what}, found ${describe(n)}`);
    }
    const t = this.next();
    const ok = t.kind === 'number' || t.kind === 'typed' || t.kind === 'string' || (t.kind === 'ident' && /^(TRUE|FALSE)$/i.test(t.text));
    if (!ok) throw this.error(t, `expected a start value for ${what} (such as 12.5, TRUE, 'text' or T#5s), found ${describe(t)}`);
    return { text: sign + t.text, at: this.pos(first) };
  }

  /** `Motor.Speed := 12.5;` `Step[3].Temp := 1.0;` `"Motor 1".Run := TRUE;` */
  private assignment(): DataBlockDecl['startValues'][number] {
    const first = this.peek();
    const path = this.path();
    this.expectPunct(':=', `expected ':=' after ${path}`);
    const value = this.startValue(path);
    const semi = this.peek();
    if (!this.isPunct(';')) throw this.error(semi, `expected ';' after the start value of ${path}, found ${describe(semi)}`);
    this.next();
    return { path, value, at: this.pos(first) };
  }

  /**
   * A member path as written, without blanks: names joined by `.`, a quoted
   * name kept in its quotes (`"Motor 1".Run`, `"Speed.Set"`), indices as
   * `[3]` or `[1,2]` (negative ones too).
   */
  private path(): string {
    let path = '';
    for (;;) {
      const t = this.next();
      if (t.kind !== 'ident' && t.kind !== 'quoted') {
        throw this.error(
          t,
          path === ''
            ? `expected a member name or END_DATA_BLOCK, found ${describe(t)}`
            : `expected a member name after ${path}., found ${describe(t)}`,
        );
      }
      path += t.kind === 'quoted' ? `"${t.text}"` : t.text;
      while (this.isPunct('[')) {
        this.next();
        const indices: number[] = [];
        for (;;) {
          indices.push(this.bound(path));
          if (this.isPunct(']')) break;
          this.expectPunct(',', `expected ',' or ']' in the index of ${path}`);
        }
        this.next();
        path += `[${indices.join(',')}]`;
      }
      if (!this.isPunct('.')) return path;
      this.next();
      path += '.';
    }
  }

  // ------------------------------------------------------------ tokens

  private peek(ahead = 0): Token {
    return this.code[Math.min(this.i + ahead, this.code.length - 1)]!;
  }

  private next(): Token {
    const t = this.peek();
    if (t.kind !== 'eof') this.i++;
    return t;
  }

  private isPunct(text: string, ahead = 0): boolean {
    const t = this.peek(ahead);
    return t.kind === 'punct' && t.text === text;
  }

  private expectPunct(text: string, problem: string): Token {
    const t = this.peek();
    if (!this.isPunct(text)) throw this.error(t, `${problem}, found ${describe(t)}`);
    return this.next();
  }

  private expectWord(word: string, problem: string): void {
    const t = this.peek();
    if (upper(t) !== word) throw this.error(t, `${problem}, found ${describe(t)}`);
    this.next();
  }

  private pos(t: Token): SourcePosition {
    return { file: this.file, line: t.line, column: t.column };
  }

  private error(t: Token, problem: string): SourceError {
    return new SourceError(this.pos(t), problem);
  }
}

/** The S7_Optimized_Access entry of an attribute record (names in any case). */
function optimizedAttribute<T>(attributes: Readonly<Record<string, T>>): T | undefined {
  const key = Object.keys(attributes).find((k) => k.toUpperCase() === 'S7_OPTIMIZED_ACCESS');
  return key === undefined ? undefined : attributes[key];
}

/** An attribute's or header's quoted value without its quotes (`''` is one quote). */
function unquote(text: string): string {
  return text.slice(1, -1).replace(/''/g, "'");
}
