/**
 * Test connection of the Node-RED connection dialog (POST /plcwire/doctor in
 * nodes/connection.js), without Node-RED: the request's fields checked and
 * bounded, the walk of diagnose() with the dialog's symbol sources, a `symbols`
 * step when those do not compile (names left out, addresses still checked),
 * the PLC's password asked for only when the URL's driver takes one, and a
 * rejection turned into an answer. Nothing is written to the PLC.
 */
import { parseAddress } from '../address';
import { DRIVERS } from '../drivers';
import type { SymbolTable } from '../symbols/model';
import { parseUrl } from '../url';
import { diagnose } from './index';
import type { DoctorReport, DoctorStep } from '../doctor-steps';

/** The longest a Test connection may take (the doctor's deadline; a request may ask for less). */
const TEST_CONNECTION_MS = 15_000;

/** Addresses and names one request may have checked at most. */
const MAX_ADDRESSES = 100;

/** The words of the `symbols` step, in the editor's language (the node's locale). */
interface SourcesStepWords {
  /** The sources do not compile: `problem` is the first error, with its file and line. */
  sources(problem: string): string;
  /** `n` more errors after the first. */
  more(n: number): string;
  /** The names left unchecked, comma-separated. */
  namesNotChecked(names: string): string;
  /** What to do about it. */
  sourcesHint: string;
}

export interface TestConnectionRequest {
  /** The request's body as the editor posts it: { url, addresses?, timeout?, strictSymbols? }. */
  body: { url?: unknown; addresses?: unknown; timeout?: unknown; strictSymbols?: unknown };
  /** The dialog's symbol sources, compiled as the connection node compiles them at start: a table, or why not. */
  compiled: { table?: SymbolTable; problems?: readonly { message: string }[] };
  /** The PLC's password of the request (typed in the dialog, or the node's credential); asked only for a driver that takes one. */
  password(): string | undefined;
  /** Aborted when the editor is gone: the walk then ends and closes its sockets. */
  signal: AbortSignal;
  words: SourcesStepWords;
}

/** The report, or one failed `doctor` step and the error's code when the walk was cut short. */
export interface TestConnectionAnswer extends DoctorReport {
  code?: string;
}

/** Whether text is an S7 address (anything else the doctor takes for a name). */
function isAddress(text: string): boolean {
  try {
    parseAddress(text);
    return true;
  } catch {
    return false;
  }
}

/** Whether the driver of `url` takes a password; false for a URL that does not parse (the walk's url step says why). */
function takesPassword(url: string): boolean {
  try {
    return DRIVERS[parseUrl(url).protocol].password;
  } catch {
    return false;
  }
}

/** Runs a Test connection; always resolves (an answer for the editor). */
export async function testConnection(request: TestConnectionRequest): Promise<TestConnectionAnswer> {
  const { body, compiled, signal, words } = request;
  const url = typeof body.url === 'string' ? body.url.trim() : '';
  const password = takesPassword(url) ? request.password() : undefined;
  let addresses = Array.isArray(body.addresses) ? body.addresses.slice(0, MAX_ADDRESSES).map(String) : [];
  let sourcesStep: DoctorStep | undefined;
  if (compiled.problems && compiled.problems.length > 0) {
    // Names cannot be looked up: they are left out, and one step says why, with the file and line of the first error.
    const names = addresses.filter((a) => !isAddress(a));
    addresses = addresses.filter(isAddress);
    const more = compiled.problems.length > 1 ? words.more(compiled.problems.length - 1) : '';
    sourcesStep = {
      step: 'symbols',
      ok: false,
      detail: words.sources(compiled.problems[0]!.message) + more + (names.length > 0 ? words.namesNotChecked(names.join(', ')) : ''),
      hint: words.sourcesHint,
    };
  }
  const asked = Number(body.timeout);
  const timeout = asked > 0 ? Math.min(asked, TEST_CONNECTION_MS) : TEST_CONNECTION_MS;
  let answer: TestConnectionAnswer;
  try {
    answer = await diagnose(url, addresses, {
      timeout,
      signal,
      ...(compiled.table ? { symbols: compiled.table, strictSymbols: body.strictSymbols === true } : {}),
      ...(password !== undefined ? { password } : {}),
    });
  } catch (err) {
    // ABORTED while the request is still there: the deadline ended the walk in the middle of a step.
    const e = err as { code?: string; message?: string } | undefined;
    const late = e?.code === 'ABORTED' && !signal.aborted;
    const detail = late ? `no result within ${timeout} ms` : e?.message ? e.message : String(err);
    const code = late ? 'TIMEOUT' : e?.code;
    answer = { ok: false, steps: [{ step: 'doctor', ok: false, detail }], ...(code !== undefined ? { code } : {}) };
  }
  return sourcesStep ? { ...answer, ok: false, steps: [...answer.steps, sourcesStep] } : answer;
}
