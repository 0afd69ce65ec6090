/**
 * Tokens of PLC block sources: TIA Portal's "Generate source from blocks"
 * (.db, .udt, .scl) and STEP 7's AWL sources. Both spell keywords in any
 * case, quote block and member names in double quotes, strings in single
 * quotes, and write typed literals with a `#` (`T#5s`, `16#FF`, `W#16#FF`,
 * `DT#90-1-1-0:0:0.000`, `B#(1, 2)`, `WSTRING#'abc'`).
 *
 * Comments: `// …` to the end of the line, `(* … *)` and `/* … *\/`. They
 * do not nest: the first `*)` ends a `(*` comment, as in TIA Portal's SCL
 * and in STEP 7's SCL with its default settings (its compiler option
 * "Permit nested comments" is off unless the user switches it on).
 *
 * `TITLE = …` takes the rest of its line as it is (both tools write the
 * title unquoted, so it may hold any character), which is why the title is
 * read here and not by the parser.
 */
import { SourceError } from '../errors';

type TokenKind =
  /** A keyword or name: `STRUCT`, `Speed`, `Bool`. */
  | 'ident'
  /** `"Motor 1"`: `text` is the name without quotes. */
  | 'quoted'
  /** `'it''s'` as written, quotes included. */
  | 'string'
  /** `12`, `1.5`, `1.000000e+000`, `1_000`. */
  | 'number'
  /** Anything with a `#`: `T#1h2m`, `16#FF`, `W#16#FF`, `B#(1,2)`, `STRING#'a'`. */
  | 'typed'
  /** The rest of a `TITLE =` line, trimmed. */
  | 'title'
  | 'comment'
  | 'punct'
  | 'eof';

export interface Token {
  readonly kind: TokenKind;
  /** As written; quoted names without their quotes; comments without `//`, `(*`, `*)`, trimmed. */
  readonly text: string;
  readonly line: number;
  readonly column: number;
}

/** Longest first. The operators beyond what declarations use appear in the code blocks of an .scl file, which the parser skips. */
const PUNCT = [
  ':=',
  '..',
  '<>',
  '<=',
  '>=',
  '**',
  '=>',
  ':',
  ';',
  ',',
  '.',
  '[',
  ']',
  '(',
  ')',
  '{',
  '}',
  '=',
  '-',
  '+',
  '*',
  '/',
  '<',
  '>',
  '&',
  '#',
  '%',
];
/** PUNCT by first character, longest first. */
const PUNCT_BY_FIRST = new Map<string, string[]>();
for (const p of PUNCT) PUNCT_BY_FIRST.set(p[0]!, [...(PUNCT_BY_FIRST.get(p[0]!) ?? []), p]);
const isLetter = (c: number) => (c >= 0x41 && c <= 0x5a) || (c >= 0x61 && c <= 0x7a) || c === 0x5f; // A-Z a-z _
const isDigit = (c: number) => c >= 0x30 && c <= 0x39;
const isIdentPart = (c: number) => isLetter(c) || isDigit(c);
/** What a typed literal after `#` may hold: digits, letters, `_ : . - +` and further `#` (`W#16#FF`). */
const isTypedPart = (c: number) => isIdentPart(c) || c === 0x3a || c === 0x2e || c === 0x23 || c === 0x2b || c === 0x2d;

/** Splits `text` into tokens; comments are kept (the parser takes a declaration's trailing comment from them). */
export function tokenize(text: string, file: string): Token[] {
  const tokens: Token[] = [];
  let i = 0;
  let line = 1;
  let lineStart = 0;
  const at = (offset: number) => ({ file, line, column: offset - lineStart + 1 });
  const push = (kind: TokenKind, tokenText: string, start: number) =>
    tokens.push({ kind, text: tokenText, line, column: start - lineStart + 1 });
  /** Moves i to `to`, counting the line ends passed. */
  const advance = (to: number) => {
    for (; i < to; i++) {
      if (text[i] === '\n') {
        line++;
        lineStart = i + 1;
      }
    }
  };

  while (i < text.length) {
    const c = text[i]!;
    const code = text.charCodeAt(i);
    const start = i;
    if (code === 0x0a) {
      line++;
      lineStart = ++i;
      continue;
    }
    if (code === 0x20 || code === 0x09 || code === 0x0d || code === 0x0c || code === 0x0b || code === 0xa0) {
      i++;
      continue;
    }
    const two = code === 0x2f || code === 0x28 ? text.slice(i, i + 2) : '';
    if (two === '//') {
      let end = text.indexOf('\n', i);
      if (end < 0) end = text.length;
      push('comment', text.slice(i + 2, end).trim(), start);
      advance(end);
      continue;
    }
    if (two === '(*' || two === '/*') {
      const close = two === '(*' ? '*)' : '*/';
      const end = text.indexOf(close, i + 2);
      if (end < 0) {
        const opened = at(start);
        throw new SourceError(opened, `unterminated comment started at ${opened.line}:${opened.column} (no ${close} follows)`);
      }
      push('comment', text.slice(i + 2, end).trim(), start);
      advance(end + 2);
      continue;
    }
    if (c === '"') {
      const end = text.indexOf('"', i + 1);
      const nl = text.indexOf('\n', i + 1);
      if (end < 0 || (nl >= 0 && nl < end)) throw new SourceError(at(start), 'unterminated name: the closing " is missing on this line');
      push('quoted', text.slice(i + 1, end), start);
      advance(end + 1);
      continue;
    }
    if (c === "'") {
      const end = stringEnd(text, i);
      if (end < 0) throw new SourceError(at(start), "unterminated string: the closing ' is missing on this line");
      push('string', text.slice(i, end), start);
      advance(end);
      continue;
    }
    const digit = isDigit(code);
    if (digit || isLetter(code)) {
      let end = i + 1;
      if (digit) end = numberEnd(text, i);
      else while (end < text.length && isIdentPart(text.charCodeAt(end))) end++;
      if (text[end] === '#') {
        end = typedEnd(text, end + 1);
        if (end < 0)
          throw new SourceError(
            at(start),
            `unterminated literal ${text
              .slice(start, start + 20)
              .split('\n')[0]!
              .trim()}`,
          );
        push('typed', text.slice(i, end), start);
        advance(end);
        continue;
      }
      const word = text.slice(i, end);
      push(digit ? 'number' : 'ident', word, start);
      i = end; // no line end inside a word
      if (word.length === 5 && word.toUpperCase() === 'TITLE') readTitle();
      continue;
    }
    const p = PUNCT_BY_FIRST.get(c)?.find((s) => s.length === 1 || text.startsWith(s, i));
    if (p === undefined) {
      const visible = code > 0x20 && code < 0x7f;
      const shown = visible ? c : `U+${code.toString(16).toUpperCase().padStart(4, '0')}`;
      throw new SourceError(at(start), `unexpected character ${shown}`);
    }
    push('punct', p, start);
    i += p.length;
  }
  tokens.push({ kind: 'eof', text: '', line, column: i - lineStart + 1 });
  return tokens;

  /** After `TITLE`: `=` and the rest of the line become one title token (an empty title too). */
  function readTitle(): void {
    let j = i;
    while (text[j] === ' ' || text[j] === '\t') j++;
    if (text[j] !== '=') return;
    push('punct', '=', j);
    let end = text.indexOf('\n', j);
    if (end < 0) end = text.length;
    push('title', text.slice(j + 1, end).trim(), j + 1);
    advance(end);
  }
}

/** The index after a string's closing quote (`''` and `$'` do not close it), or -1 when the line ends first. */
function stringEnd(text: string, open: number): number {
  for (let j = open + 1; j < text.length; j++) {
    const ch = text[j];
    if (ch === '\n') return -1;
    if (ch === '$') j++;
    else if (ch === "'") {
      if (text[j + 1] === "'") j++;
      else return j + 1;
    }
  }
  return -1;
}

/** The end of `12`, `1_000`, `1.5`, `1.5E-3`; `1..10` stops before the `..`. */
function numberEnd(text: string, start: number): number {
  let j = start;
  const digits = () => {
    while (j < text.length && (isDigit(text.charCodeAt(j)) || text[j] === '_')) j++;
  };
  digits();
  if (text[j] === '.' && isDigit(text.charCodeAt(j + 1))) {
    j++;
    digits();
  }
  if ((text[j] === 'e' || text[j] === 'E') && /^[+-]?[0-9]/.test(text.slice(j + 1, j + 3))) {
    j += text[j + 1] === '+' || text[j + 1] === '-' ? 2 : 1;
    digits();
  }
  return j;
}

/** The end of a typed literal's value after its `#`: a quoted string, a parenthesised byte list, or a run of literal characters. */
function typedEnd(text: string, from: number): number {
  if (text[from] === "'") return stringEnd(text, from);
  if (text[from] === '(') {
    const close = text.indexOf(')', from);
    const nl = text.indexOf('\n', from);
    return close < 0 || (nl >= 0 && nl < close) ? -1 : close + 1;
  }
  let j = from;
  while (j < text.length && isTypedPart(text.charCodeAt(j))) j++;
  return j === from ? -1 : j;
}
