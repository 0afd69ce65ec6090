/**
 * Blocks, members, types and array indices as TIA Portal writes them, for
 * the names a layout gives its members (layout.ts, compile.ts) and for the
 * places its messages name.
 */
import type { DataTypeName } from '../types';
import type { TypeDecl } from './model';
import type { ArrayNode } from './layout-nodes';
import { isSystemDecl } from './system-types';

/** How TIA Portal spells each type in its editors and sources (`Bool`, `DInt`, `Time_Of_Day`). */
export const TIA_SPELLING: Readonly<Record<DataTypeName, string>> = Object.freeze({
  BOOL: 'Bool',
  BYTE: 'Byte',
  WORD: 'Word',
  DWORD: 'DWord',
  LWORD: 'LWord',
  SINT: 'SInt',
  USINT: 'USInt',
  INT: 'Int',
  UINT: 'UInt',
  DINT: 'DInt',
  UDINT: 'UDInt',
  LINT: 'LInt',
  ULINT: 'ULInt',
  REAL: 'Real',
  LREAL: 'LReal',
  CHAR: 'Char',
  WCHAR: 'WChar',
  STRING: 'String',
  WSTRING: 'WString',
  S5TIME: 'S5Time',
  TIME: 'Time',
  LTIME: 'LTime',
  DATE: 'Date',
  TIME_OF_DAY: 'Time_Of_Day',
  DATE_AND_TIME: 'Date_And_Time',
  DTL: 'DTL',
  COUNTER: 'Counter',
  TIMER: 'Timer',
});

/** A name needs no quotes when it is a plain identifier (letters, umlauts included, digits, `_`), as names.ts reads them. */
const PLAIN_NAME = /^[\p{L}_][\p{L}\p{M}\p{N}_]*$/u;

/** A block as TIA writes it: `"Tank"`; a STEP 7 DB without symbol as STEP 7 does: `DB10`. */
export function blockRef(decl: { readonly name: string; readonly number?: number }): string {
  return decl.number !== undefined && decl.name.toUpperCase() === `DB${decl.number}` ? `DB${decl.number}` : `"${decl.name}"`;
}

/** A member as TIA writes it after the dot: `Speed`, or quoted when not a plain identifier: `"Speed.Set"`. */
export function memberRef(name: string): string {
  return PLAIN_NAME.test(name) ? name : `"${name}"`;
}

/** A UDT as TIA writes it: `"Motor"`; a STEP 7 UDT without symbol: `UDT 5`. */
export function typeRef(decl: TypeDecl): string {
  if (isSystemDecl(decl)) return decl.name;
  return decl.number !== undefined && decl.name.toUpperCase() === `UDT${decl.number}` ? `UDT ${decl.number}` : `"${decl.name}"`;
}

/** Where a member is, for messages: built only when a message needs it. */
export interface Where {
  readonly parent?: Where;
  /** `"Tank"`, `.Speed`, `[3]`. */
  readonly segment: string;
}

export function whereText(where: Where): string {
  let text = '';
  for (let w: Where | undefined = where; w; w = w.parent) text = w.segment + text;
  return text;
}

export function child(where: Where, name: string): Where {
  return { parent: where, segment: `.${memberRef(name)}` };
}

/** The indices of element `k` of an array (last index fastest), as TIA writes them: `3`, `1,2`. */
export function elementIndex(dims: ArrayNode['dims'], k: number): string {
  const indices: number[] = new Array<number>(dims.length);
  let rest = k;
  for (let d = dims.length - 1; d >= 0; d--) {
    const span = dims[d]!.high - dims[d]!.low + 1;
    indices[d] = dims[d]!.low + (rest % span);
    rest = Math.floor(rest / span);
  }
  return indices.join(',');
}
