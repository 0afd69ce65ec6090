/**
 * One error family for every driver. Each error has a stable `code` users can
 * switch on, the tag/address it concerns (when there is one) and the original
 * `cause`. Errors are raised once, where they happen, and carried upwards.
 */

export type PlcErrorCode =
  // input validation (nothing was sent)
  | 'INVALID_ADDRESS'
  | 'INVALID_VALUE'
  | 'INVALID_URL'
  /** A DB/UDT source or a symbol table could not be compiled (syntax, unknown type, optimized block). */
  | 'INVALID_SOURCE'
  | 'WRITE_NOT_ALLOWED'
  /**
   * Two connections reach the same PLC (and share its one client) but disagree
   * on settings they must share: readOnly, allow, control or the symbol
   * sources. Each URL is valid on its own.
   */
  | 'SETTINGS_CONFLICT'
  // link state
  | 'NOT_CONNECTED'
  | 'CONNECTION_LOST'
  | 'CONNECT_FAILED'
  | 'CLOSED'
  | 'TIMEOUT'
  | 'ABORTED'
  | 'QUEUE_FULL'
  // the peer misbehaved (malformed, truncated or hostile frames)
  | 'PROTOCOL_ERROR'
  /**
   * The PLC's TLS certificate was refused (not pinned, wrong pin, expired, not
   * yet valid, not signed by the given CA): nothing was sent to it. The error
   * shows the certificate and the `fingerprint=` that would pin it.
   */
  | 'CERTIFICATE_UNTRUSTED'
  // the PLC answered with an error
  | 'PLC_ERROR'
  | 'ACCESS_DENIED'
  | 'ADDRESS_OUT_OF_RANGE'
  | 'OBJECT_DOES_NOT_EXIST'
  | 'PDU_TOO_LARGE'
  | 'TYPE_NOT_SUPPORTED'
  /** The PLC's data block no longer has the length its sources declare (with strictSymbols). */
  | 'LAYOUT_MISMATCH'
  /** A name in a data block with optimized access, asked of a protocol that reads by address (s7://, fetchwrite://): nothing was sent. */
  | 'OPTIMIZED_BLOCK'
  /** The CPU has no such SZL list (ID or index). */
  | 'SZL_NOT_AVAILABLE'
  /** The CPU family does not offer the service at all. */
  | 'NOT_SUPPORTED'
  // one or more tags of a multi-tag request failed
  | 'TAG_ERRORS';

export interface PlcErrorOptions {
  /** The tag name or address as the user gave it. */
  tag?: string;
  /** A return code from the PLC, when there is one. */
  plcCode?: number;
  cause?: unknown;
}

export class PlcError extends Error {
  readonly code: PlcErrorCode;
  readonly tag?: string;
  readonly plcCode?: number;

  constructor(code: PlcErrorCode, message: string, options: PlcErrorOptions = {}) {
    super(message, options.cause === undefined ? undefined : { cause: options.cause });
    this.name = new.target.name;
    this.code = code;
    if (options.tag !== undefined) this.tag = options.tag;
    if (options.plcCode !== undefined) this.plcCode = options.plcCode;
  }
}

/**
 * An address or tag name inside a message, quoted once: in double quotes
 * (`"DB1.DBW"`, `"Tank.Level"`), or as written when it is a name in TIA's
 * quotes (`"Tank".Level`, not `""Tank".Level"`). Other text with a double
 * quote (an odd one, or at an end beside a space) is written as a JSON
 * string (`"\""`), so that where it starts and ends stays clear.
 */
export function quoteTag(text: string): string {
  if (!text.includes('"')) return `"${text}"`;
  const balanced = text.split('"').length % 2 === 1;
  return balanced && text.trim() === text && text !== '' ? text : JSON.stringify(text);
}

/** A malformed address. Thrown by the parsers before anything is sent. */
export class AddressError extends PlcError {
  /** What is wrong with the address, without the address and the hint. */
  readonly problem: string;

  /** `hint`: what to do, after the problem (`; …`). */
  constructor(address: string, problem: string, hint?: string) {
    super('INVALID_ADDRESS', `invalid address ${quoteTag(address)}: ${problem}${hint ? `; ${hint}` : ''}`, { tag: address });
    this.problem = problem;
  }
}

/**
 * A source file (DB, UDT, symbol table) that cannot be compiled. The message
 * starts with `file:line:column`; the fields say the same for programs.
 */
export class SourceError extends PlcError {
  readonly file: string;
  readonly line: number;
  readonly column: number;

  constructor(at: { file: string; line: number; column: number }, problem: string) {
    super('INVALID_SOURCE', `${at.file}:${at.line}:${at.column}: ${problem}`);
    this.file = at.file;
    this.line = at.line;
    this.column = at.column;
  }
}

/**
 * A name in a data block with optimized access asked of a protocol that
 * reads by absolute address (S7comm PUT/GET, FETCH/WRITE): such a block has
 * no fixed offsets, so its members are read by name over S7CommPlus
 * (`s7plus://`). Thrown before anything is sent; the message names the tag
 * and the block.
 */
export class OptimizedBlockError extends PlcError {
  /** The block as its sources name it: `Tank`, `DB10`. */
  readonly block: string;
  readonly db: number;

  constructor(tag: string, block: string, db: number) {
    const which = block === `DB${db}` ? block : `DB${db} "${block}"`;
    super(
      'OPTIMIZED_BLOCK',
      `${quoteTag(tag)} is in ${which}, a block with optimized access: it has no absolute address to read or write by. ` +
        `Read it by name over s7plus:// (S7CommPlus), or untick "Optimized block access" in the block's properties in TIA Portal, ` +
        'download it and use PUT/GET',
      { tag },
    );
    this.block = block;
    this.db = db;
  }
}

/** A value that does not fit its tag's type. Thrown before anything is sent. */
export class ValueError extends PlcError {
  constructor(tag: string, problem: string) {
    super('INVALID_VALUE', `invalid value for ${quoteTag(tag)}: ${problem}`, { tag });
  }
}

/** The peer sent something that does not follow the protocol. The link is dropped. */
export class ProtocolError extends PlcError {
  constructor(message: string, options: PlcErrorOptions = {}) {
    super('PROTOCOL_ERROR', message, options);
  }
}

/** A request did not complete within its deadline. */
export class TimeoutError extends PlcError {
  constructor(message: string, options: PlcErrorOptions = {}) {
    super('TIMEOUT', message, options);
  }
}

/** The link is down, was lost, or could not be established. */
export class ConnectionError extends PlcError {}

/**
 * Some tags of a multi-tag read or write failed. The others succeeded:
 * `results` has every tag's outcome, keyed as given.
 */
export class TagErrors<T = unknown> extends PlcError {
  readonly results: Record<string, TagResult<T>>;
  readonly errors: Record<string, PlcError>;

  constructor(results: Record<string, TagResult<T>>) {
    const errors: Record<string, PlcError> = {};
    for (const [key, r] of Object.entries(results)) if (!r.ok) errors[key] = r.error;
    const keys = Object.keys(errors);
    const first = errors[keys[0]!];
    const more = keys.length > 1 ? ` (and ${keys.length - 1} more failed tag${keys.length > 2 ? 's' : ''})` : '';
    super('TAG_ERRORS', `${first ? first.message : 'tags failed'}${more}`, { tag: keys[0], cause: first });
    this.results = results;
    this.errors = errors;
  }
}

/**
 * True when the PLC refused a subscription for what it is, not for a passing
 * reason: NOT_SUPPORTED, or every tag NOT_SUPPORTED (an S7-1200/1500 asked
 * for cyclic data over s7://). A caller then polls instead of subscribing
 * again (the read node says push is not possible; a Sparkplug device is
 * polled).
 */
export function refusedForGood(err: PlcError): boolean {
  if (err.code === 'NOT_SUPPORTED') return true;
  return err instanceof TagErrors && Object.values(err.errors).every((e) => e.code === 'NOT_SUPPORTED');
}

export type TagResult<T = unknown> = { ok: true; value: T } | { ok: false; error: PlcError };

/**
 * The error of a request (or connection attempt, or command) given up before
 * its answer: because `signal` was aborted (its reason is the cause), or, with
 * no signal, because the caller gave up on it. The one place an ABORTED error
 * is made, so every abort reads the same ("… was aborted").
 */
export function abortError(description: string, signal?: AbortSignal): PlcError {
  return new PlcError('ABORTED', `${description} was aborted`, signal ? { cause: signal.reason } : {});
}

/**
 * The same error for one tag: names the tag (and `where` it lies, when that
 * says more than the address as written), keeps the code and the PLC's
 * return code. An error that names the tag already is returned as it is.
 */
export function tagError(address: string, err: PlcError, where?: string): PlcError {
  if (err.tag === address) return err;
  return new PlcError(err.code, `${address}${where ? ` (${where})` : ''}: ${err.message}`, {
    tag: address,
    ...(err.plcCode === undefined ? {} : { plcCode: err.plcCode }),
    cause: err,
  });
}

/**
 * True for an error of the link rather than of a tag or a request: the
 * client is not connected, could not connect, lost the connection or was
 * closed. The request never reached a PLC, or its answer can no longer come;
 * the supervisor reconnects (unless closed) and the state events tell it.
 */
export function isLinkError(err: unknown): boolean {
  // By code, not instanceof: an error from another copy of this package counts as well.
  const code = typeof err === 'object' && err !== null ? (err as { code?: unknown }).code : undefined;
  return code === 'NOT_CONNECTED' || code === 'CONNECT_FAILED' || code === 'CONNECTION_LOST' || code === 'CLOSED';
}

/**
 * True for a refusal that another attempt in a second will not change: the
 * PLC refused our password or rights (ACCESS_DENIED), or offers no way to
 * do what the connection asks (NOT_SUPPORTED). The supervisor still retries
 * (the PLC's configuration may change), but at its longest delay from the
 * first retry, so a wrong password does not knock on the PLC every second.
 */
export function isLastingRefusal(err: unknown): boolean {
  const code = typeof err === 'object' && err !== null ? (err as { code?: unknown }).code : undefined;
  return code === 'ACCESS_DENIED' || code === 'NOT_SUPPORTED';
}

/** Wraps anything thrown into a PlcError, keeping PlcErrors as they are. */
export function toPlcError(err: unknown, fallback: PlcErrorCode = 'CONNECTION_LOST'): PlcError {
  if (err instanceof PlcError) return err;
  const message = err instanceof Error ? err.message : String(err);
  return new PlcError(fallback, message, { cause: err });
}

/**
 * A write refused as a whole (not connected, the link lost, the queue full,
 * aborted): the same code and kind of error, naming the tags it was for, so
 * a log says which write failed (issue #26). An error that names a tag
 * already is returned as it is.
 */
export function writeRefusal(keys: readonly string[], err: unknown): PlcError {
  const e = toPlcError(err);
  if (keys.length === 0 || e.tag !== undefined) return e;
  const Kind = e instanceof ConnectionError ? ConnectionError : PlcError;
  return new Kind(e.code, `write ${keys.map(quoteTag).join(', ')}: ${e.message}`, {
    ...(keys.length === 1 ? { tag: keys[0]! } : {}),
    ...(e.plcCode === undefined ? {} : { plcCode: e.plcCode }),
    cause: e,
  });
}
