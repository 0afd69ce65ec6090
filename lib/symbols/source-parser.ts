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
 *
 * This file reads the blocks and their headers; the declarations and start
 * values are in source-declarations.ts, the token cursor in source-cursor.ts.
 */
import { SourceError } from '../errors';
import { tokenize, type Token } from './lexer';
import type { BlockDecl, DataBlockDecl, MemberDecl, SymbolSource, TypeDecl, TypeRef } from './model';
import { BLOCK_ENDS, SECTION_WORDS, describe, unquote, upper } from './source-cursor';
import { DeclarationParser, type StructRef } from './source-declarations';

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

/** The blocks of one source: TYPE and DATA_BLOCK with their headers and bodies, code blocks skipped. */
class Parser extends DeclarationParser {
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

  private skipBlock(end: string): void {
    const open = this.next();
    for (;;) {
      const t = this.next();
      if (upper(t) === end) return;
      if (t.kind === 'eof') throw this.error(t, `${end} missing for ${open.text.toUpperCase()} opened at ${open.line}:${open.column}`);
    }
  }
}

/** The S7_Optimized_Access entry of an attribute record (names in any case). */
function optimizedAttribute<T>(attributes: Readonly<Record<string, T>>): T | undefined {
  const key = Object.keys(attributes).find((k) => k.toUpperCase() === 'S7_OPTIMIZED_ACCESS');
  return key === undefined ? undefined : attributes[key];
}
