/**
 * The token cursor of the block source parser (source-parser.ts): the
 * tokens of a source without its comments (each declaration's line comment
 * kept beside it), how far the parser has read, how deep it nests, and the
 * SourceErrors it throws at a token. Also the pieces every part of the
 * grammar reads: `{ Name := 'Value' }` attributes and block numbers.
 */
import { SourceError } from '../errors';
import type { Token } from './lexer';
import type { SourcePosition } from './model';

/**
 * Nesting of STRUCTs, ARRAYs and start-value lists the parser follows: far
 * beyond what the engineering tools let a block nest, far within the stack.
 */
const MAX_DEPTH = 64;

/** Keywords that end a block or start the next one: a STRUCT or BEGIN section that meets one is unterminated. */
export const BLOCK_ENDS = new Set([
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
export const SECTION_WORDS = new Set(['VAR', 'END_VAR', 'STRUCT', 'END_STRUCT', 'VAR_INPUT', 'VAR_OUTPUT', 'VAR_IN_OUT', 'VAR_TEMP']);

/** An identifier in upper case (keywords are case-insensitive); '' for any other token. */
export function upper(t: Token): string {
  return t.kind === 'ident' ? t.text.toUpperCase() : '';
}

/** A token as a message shows it. */
export function describe(t: Token): string {
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

/** An attribute's or header's quoted value without its quotes (`''` is one quote). */
export function unquote(text: string): string {
  return text.slice(1, -1).replace(/''/g, "'");
}

/** A source's tokens and the parser's place in them. */
export abstract class SourceCursor {
  protected readonly code: Token[];
  /** The comment that follows a token on its own line (a declaration's `// …`). */
  protected readonly trailing = new Map<Token, string>();
  protected i = 0;
  /** STRUCT, ARRAY and start-value brackets open now; bounded so a hostile file cannot exhaust the stack. */
  protected depth = 0;

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

  // ------------------------------------------------------------ tokens

  protected peek(ahead = 0): Token {
    return this.code[Math.min(this.i + ahead, this.code.length - 1)]!;
  }

  protected next(): Token {
    const t = this.peek();
    if (t.kind !== 'eof') this.i++;
    return t;
  }

  protected isPunct(text: string, ahead = 0): boolean {
    const t = this.peek(ahead);
    return t.kind === 'punct' && t.text === text;
  }

  protected expectPunct(text: string, problem: string): Token {
    const t = this.peek();
    if (!this.isPunct(text)) throw this.error(t, `${problem}, found ${describe(t)}`);
    return this.next();
  }

  protected expectWord(word: string, problem: string): void {
    const t = this.peek();
    if (upper(t) !== word) throw this.error(t, `${problem}, found ${describe(t)}`);
    this.next();
  }

  protected pos(t: Token): SourcePosition {
    return { file: this.file, line: t.line, column: t.column };
  }

  protected error(t: Token, problem: string): SourceError {
    return new SourceError(this.pos(t), problem);
  }

  /** Runs a nested part of a declaration, refusing nesting deeper than MAX_DEPTH. */
  protected nested<T>(what: string, read: () => T): T {
    if (this.depth >= MAX_DEPTH) throw this.error(this.peek(), `${what} is nested deeper than ${MAX_DEPTH} levels`);
    this.depth++;
    try {
      return read();
    } finally {
      this.depth--;
    }
  }

  /** The comment after the first line of a declaration (for a STRUCT member: after `Struct`, as TIA and STEP 7 write it). */
  protected lineComment(first: number): string {
    let last = first;
    while (this.code[last + 1] && this.code[last + 1]!.line === this.code[first]!.line && last + 1 < this.i) last++;
    return this.trailing.get(this.code[last]!) ?? '';
  }

  /** `{ Name := 'Value'; … }` into `into`; returns where each name was written. */
  protected attributes(into: Record<string, string>): Record<string, Token> {
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

  protected numbered(prefix: string, digits: string, at: Token): { name: string; number: number } {
    const n = Number(digits);
    if (!/^\d+$/.test(digits) || n < 1 || n > 65535) throw this.error(at, `${prefix} number ${digits} is not a block number (1..65535)`);
    return { name: `${prefix}${n}`, number: n };
  }
}
