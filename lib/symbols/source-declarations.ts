/**
 * The declarations of the block source parser (source-parser.ts): members
 * and their types (elementary, STRING lengths, ARRAY bounds, STRUCTs, UDTs
 * by name or number), and start values (literals, lists, repeat factors)
 * with the member paths of a BEGIN section. The same grammar in TIA and
 * STEP 7 sources.
 */
import { SourceError } from '../errors';
import { MAX_STRING_LENGTH, MAX_WSTRING_LENGTH } from '../address/sizes';
import type { DataTypeName } from '../types';
import { JS_TYPES } from '../values';
import type { Token } from './lexer';
import { isSystemTypeName } from './system-types';
import type { DataBlockDecl, Literal, MemberDecl, StartValue, StartValueItem, TypeRef } from './model';
import { BLOCK_ENDS, SourceCursor, describe, upper } from './source-cursor';
import { distance } from './distance';

export type StructRef = Extract<TypeRef, { kind: 'struct' }>;

/** The elementary types by their IEC names (any case), and the short forms both tools accept in declarations. */
const ELEMENTARY: ReadonlyMap<string, DataTypeName> = new Map<string, DataTypeName>([
  ...(Object.keys(JS_TYPES) as DataTypeName[]).map((t) => [t, t] as const),
  ['DT', 'DATE_AND_TIME'],
  ['TOD', 'TIME_OF_DAY'],
]);

/** Types without a fixed place in a data block's standard layout that plcwire could read: refused at the member. */
const NO_LAYOUT = new Set(['VARIANT', 'ANY', 'POINTER', 'ANY_POINTER', 'REF_TO', 'BLOCK_DB', 'BLOCK_FB', 'BLOCK_FC', 'BLOCK_SDB']);

/** Members, types and start values: what a STRUCT, a VAR section and a BEGIN section hold. */
export abstract class DeclarationParser extends SourceCursor {
  // ------------------------------------------------------------ declarations

  protected struct(open: Token): StructRef {
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

  protected member(open: Token): MemberDecl {
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

  protected typeRef(member: string): TypeRef {
    return this.nested(member, () => this.typeRefAt(member));
  }

  protected typeRefAt(member: string): TypeRef {
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

  /**
   * `UDT 5` (or glued, `UDT5`) as the named type `UDT5` with its number;
   * `FB 3` / `SFB 4` as the named type `FB3` / `SFB4` WITHOUT a number,
   * since a number on a named type means a UDT (model.ts) and an instance
   * DB of FB 5 must not be laid out as UDT 5. Undefined when the next token
   * is none of these.
   */
  protected numberedType(): TypeRef | undefined {
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

  /** `Array[1..10] of Bool`, `ARRAY [-5 .. 5, 0 .. 2 ] OF INT`. */
  protected arrayType(member: string): TypeRef {
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

  protected bound(member: string): number {
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
  protected stringLength(type: 'STRING' | 'WSTRING', member: string): number {
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
  protected startValue(what: string): StartValue {
    return this.nested(what, () => this.startValueAt(what));
  }

  protected startValueAt(what: string): StartValue {
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

  protected items(what: string): (StartValueItem & { grouped?: boolean })[] {
    const items: (StartValueItem & { grouped?: boolean })[] = [];
    for (;;) {
      items.push(this.item(what));
      if (!this.isPunct(',')) return items;
      this.next();
    }
  }

  protected item(what: string): StartValueItem & { grouped?: boolean } {
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

  protected literal(what: string): Literal {
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
  protected assignment(): DataBlockDecl['startValues'][number] {
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
  protected path(): string {
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
}
