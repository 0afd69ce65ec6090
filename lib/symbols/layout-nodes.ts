/**
 * The tree a layout gives (layout.ts): every member of a data block placed
 * at its byte and bit, with its type as TIA shows it.
 */
import type { DataTypeName } from '../types';
import type { DataBlockDecl, MemberDecl, SourcePosition, TypeDecl } from './model';

interface Placed {
  /** Byte offset from the start of the block. */
  readonly byte: number;
  /** 0–7 for BOOL and a BOOL array (its first bit); null otherwise. */
  readonly bit: number | null;
  /** Bytes covered from `byte` (a BOOL: 1; a BOOL array: the bytes its bits touch; a struct: its even length). */
  readonly size: number;
  /** The type as TIA shows it: `Int`, `String[20]`, `Array[1..10] of Bool`, `"Motor"`, `Struct`. */
  readonly typeText: string;
  /** The member's declaration; undefined for array elements and the block itself. */
  readonly decl?: MemberDecl;
  readonly at: SourcePosition;
}

export interface ElementaryNode extends Placed {
  readonly kind: 'elementary';
  readonly dataType: DataTypeName;
  readonly stringLength: number;
}

export interface ArrayNode extends Placed {
  readonly kind: 'array';
  readonly dims: readonly { readonly low: number; readonly high: number }[];
  /** The elements, last index fastest. */
  readonly elements: readonly LayoutNode[];
  /** Elements of an elementary type: the type and its string length. */
  readonly elementType?: { readonly dataType: DataTypeName; readonly stringLength: number };
  /** True when the elements lie as one `TYPE[count]` address reads them: elementary, one after the other with no gap. */
  readonly contiguous: boolean;
}

export interface StructNode extends Placed {
  readonly kind: 'struct';
  readonly members: readonly { readonly name: string; readonly node: LayoutNode }[];
  /** The UDT it is an instance of (its declared name), when it is one. */
  readonly typeName?: string;
  /** The UDT's declaration, when it is an instance of one (its members' start values apply to every instance). */
  readonly typeDecl?: TypeDecl;
}

export type LayoutNode = ElementaryNode | ArrayNode | StructNode;

/** A data block laid out. */
export interface BlockLayout {
  readonly decl: DataBlockDecl;
  /** The block's body, at byte 0. */
  readonly root: StructNode;
  /**
   * Bytes of the block (even). A block with optimized access (decl.optimized)
   * is laid out by the same rules, for its structure and its members' sizes
   * only: the CPU places its members elsewhere, so its table has no offsets.
   */
  readonly length: number;
  /** The UDT the block is an instance of, as TIA writes it (`"Motor"`, `UDT 5`). */
  readonly instanceOf?: string;
}

export interface LayoutOptions {
  /** UDT numbers by symbol (lower case), from a symbol table: a `"Motor"` reference finds `TYPE UDT 5` through the row `Motor  UDT5`. */
  readonly typeNumbers?: ReadonlyMap<string, number>;
}
