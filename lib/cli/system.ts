/**
 * The system commands: info and blocks (whatever the URL's client offers: the
 * S7Client's services, the S7CommPlus client's CPU state and data blocks),
 * szl, diag, clock, cpu (S7 only) and doctor (lib/doctor/, each driver's steps through its diagnose port). Control (cpu, clock --set) is
 * refused before connecting unless the URL says control=true, and needs
 * --yes from a script or for a PLC that is not this machine.
 */
import { isLinkError, PlcError } from '../errors';
import type { SymbolTable } from '../symbols/model';
import { S7Client } from '../s7/client';
import { BLOCK_TYPES, type BlockType } from '../s7/constants';
import { decodeDiagnosticBuffer } from '../s7/codec/diagnostics';
import { diagnose, type DoctorStep } from '../doctor';
import { driverOf, schemesOffering } from '../drivers';
import { isS7Endpoint } from '../s7/url';
import {
  decodeCommunicationRecords,
  decodeComponentIdentification,
  decodeCpuState,
  decodeLeds,
  decodeModuleIdentification,
  decodeProtection,
  decodeSzlIds,
  type SzlList,
} from '../s7/codec/szl';
import { createClient, type AnyClient } from '../connect';
import type { RequestOptions } from '../types';
import { endpointName, isLoopback, parseUrl, type Endpoint, type S7Endpoint } from '../url';
import { UsageError, intFlag, stringFlag, withTimeout, type ParsedArgs } from './args';
import { EXIT, confirm, withClient, type CliIo } from './io';
import { passwordOption } from './s7plus';
import { symbolOptions } from './symbols';
import { toJson, valueToText } from './values';
import { hex4 } from '../values/text';

/** The S7 endpoint of the first positional; anything else is a usage error. */
function s7Endpoint(rest: string[], what: string, args: ParsedArgs): S7Endpoint {
  const url = rest[0];
  if (url === undefined) throw new UsageError(`${what} needs a PLC url`);
  const endpoint = withTimeout(parseUrl(url), args);
  if (!isS7Endpoint(endpoint)) throw new UsageError(`${what} speaks S7 only: give an s7:// URL`);
  return endpoint;
}

/** The endpoint of the first positional, any protocol: the command then asks its client what it offers. */
function anyEndpoint(rest: string[], what: string, args: ParsedArgs): Endpoint {
  const url = rest[0];
  if (url === undefined) throw new UsageError(`${what} needs a PLC url`);
  return withTimeout(parseUrl(url), args);
}

/** The services info and blocks look for on a client; each is optional, asked of the client, not of its protocol. */
interface SystemServices {
  info?(options?: RequestOptions): Promise<object>;
  cpuState?(options?: RequestOptions): Promise<unknown>;
  certificate?: { fingerprint: string; subject: string; validFrom: string; validTo: string } | undefined;
  listBlocks?(options?: RequestOptions): Promise<Record<string, number>>;
  dataBlocks?(options?: RequestOptions): Promise<{ number: number; name: string }[]>;
}

/** The URL's client (with the password of an s7plus:// URL), unconnected, seen through the services it may offer. */
function systemClient(endpoint: Endpoint, args: ParsedArgs): AnyClient & SystemServices {
  return createClient(endpoint, passwordOption(endpoint, args)) as AnyClient & SystemServices;
}

function notOffered(endpoint: Endpoint, what: string): PlcError {
  return new PlcError('NOT_SUPPORTED', `${endpointName(endpoint)}: the ${endpoint.protocol}:// client cannot ${what}`);
}

function extra(rest: string[], from: number): void {
  if (rest.length > from) throw new UsageError(`unexpected argument "${rest[from]}"`);
}

function print(io: CliIo, args: ParsedArgs, json: unknown, text: () => string[]): void {
  if (args.flags.has('json')) io.stdout.write(`${toJson(json)}\n`);
  else for (const line of text()) io.stdout.write(`${line}\n`);
}

function run<R>(endpoint: S7Endpoint, io: CliIo, work: (c: S7Client) => Promise<R>): Promise<R> {
  return withClient(new S7Client(endpoint), io, (c) => work(c as S7Client));
}

/**
 * Control of a CPU: refused (exit 4, nothing sent) without control=true in
 * the URL; from a script, or for a PLC that is not this machine, only with
 * --yes or a "y" at the prompt.
 */
async function checkControl(endpoint: S7Endpoint, args: ParsedArgs, io: CliIo, what: string): Promise<void> {
  if (endpoint.readOnly) throw new PlcError('WRITE_NOT_ALLOWED', `refusing to ${what}: the connection is read-only`);
  if (!endpoint.control)
    throw new PlcError('WRITE_NOT_ALLOWED', `refusing to ${what}: the URL does not allow PLC control (add control=true)`);
  if (args.flags.has('yes') || (io.stdin.isTTY && isLoopback(endpoint))) return;
  if (!io.stdin.isTTY) throw new PlcError('WRITE_NOT_ALLOWED', `refusing to ${what} without --yes when standard input is not a terminal`);
  if (!(await confirm(io, `${what}? [y/N] `))) throw new PlcError('WRITE_NOT_ALLOWED', `${what}: cancelled`);
}

export async function info(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = anyEndpoint(rest, 'info', args);
  extra(rest, 1);
  const client = systemClient(endpoint, args);
  const { info: full, cpuState } = client;
  if (!full && !cpuState) throw notOffered(endpoint, 'tell the CPU state or identity'); // before connecting
  const json: Record<string, unknown> = await withClient(client, io, async () => {
    if (full) return { ...(await full.call(client, { signal: io.signal })) };
    // What the client has: the state, and the certificate of its TLS session (S7CommPlus).
    const state = await cpuState!.call(client, { signal: io.signal });
    const cert = client.certificate;
    return { state, ...(cert ? { certificate: cert } : {}) };
  });
  // The state as the library and the PLC say it (RUN, STOP), as TIA Portal shows it.
  print(io, args, json, () =>
    Object.entries(json)
      .filter(([, v]) => v !== undefined)
      .map(([k, v]) => `${k}: ${k === 'protection' || k === 'certificate' ? toJson(v) : typeof v === 'string' ? v : valueToText(v)}`),
  );
  return EXIT.OK;
}

/** An SZL ID or index: hex as the manuals write them (0x0011, 0011, W#16#0011). */
function hexWord(text: string, what: string): number {
  const t = text.replace(/^(0x|W#16#)/i, '');
  if (!/^[0-9a-f]{1,4}$/i.test(t)) throw new UsageError(`${what} "${text}" is not a hex word (e.g. 0x0011)`);
  return Number.parseInt(t, 16);
}

/** The lists this library decodes, by SZL ID (the extracts whose records it reads). */
const SZL_DECODERS: ReadonlyMap<number, (l: SzlList) => unknown> = new Map<number, (l: SzlList) => unknown>([
  [0x0000, (l) => decodeSzlIds(l).map((id) => `0x${hex4(id)}`)],
  [0x0011, decodeModuleIdentification],
  [0x0111, decodeModuleIdentification],
  [0x001c, decodeComponentIdentification],
  [0x011c, decodeComponentIdentification],
  [0x0031, decodeCommunicationRecords],
  [0x0131, decodeCommunicationRecords],
  [0x0232, decodeProtection],
  [0x0424, decodeCpuState],
  [0x0019, decodeLeds],
  [0x0074, decodeLeds],
  [0x0174, decodeLeds],
  [0x00a0, decodeDiagnosticBuffer],
  [0x01a0, decodeDiagnosticBuffer],
]);

function decodeSzl(list: SzlList): unknown {
  const decode = SZL_DECODERS.get(list.id);
  if (!decode) return undefined;
  try {
    return decode(list);
  } catch {
    return undefined; // an index of that list whose records this decoder does not read
  }
}

export async function szl(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = s7Endpoint(rest, 'szl', args);
  if (rest[1] === undefined) throw new UsageError('szl needs an SZL ID (hex, e.g. 0x0011)');
  const id = hexWord(rest[1], 'SZL ID');
  const index = rest[2] === undefined ? 0 : hexWord(rest[2], 'SZL index');
  extra(rest, 3);
  const list = await run(endpoint, io, (c) => c.readSzl(id, index, { signal: io.signal }));
  const hex = (n: number) => `0x${hex4(n)}`;
  const decoded = decodeSzl(list);
  // A header-only extract (0x0Fxx) answers how many records exist: the count is the answer.
  const headerOnly = (list.id & 0x0f00) === 0x0f00;
  const count = list.count ?? list.records.length;
  const json = {
    id: hex(list.id),
    index: hex(list.index),
    recordLength: list.recordLength,
    count,
    records: list.records.map((r) => r.toString('hex')),
    decoded,
  };
  print(io, args, json, () => [
    headerOnly
      ? `SZL ${json.id} index ${json.index}: ${count} record(s) of ${list.recordLength} bytes exist (header only, none sent)`
      : `SZL ${json.id} index ${json.index}: ${list.records.length} record(s) of ${list.recordLength} bytes`,
    ...json.records.map((r, n) => `  ${n}: ${r}`),
    ...(decoded === undefined ? [] : [`decoded: ${toJson(decoded)}`]),
  ]);
  return EXIT.OK;
}

export async function diag(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = s7Endpoint(rest, 'diag', args);
  extra(rest, 1);
  const max = args.flags.has('max') ? intFlag(args, 'max', 10, 1, 65535) : undefined;
  const entries = await run(endpoint, io, (c) => c.diagnosticBuffer({ signal: io.signal, ...(max !== undefined ? { max } : {}) }));
  const hex = (n: number) => `0x${hex4(n)}`;
  const json = entries.map((e) => ({ ...e, eventId: hex(e.eventId) }));
  print(io, args, json, () =>
    json.map((e) => `${Number.isNaN(e.time.getTime()) ? '(no valid time)' : e.time.toISOString()}  ${e.eventId}  ${e.description}`),
  );
  return EXIT.OK;
}

export async function clock(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = s7Endpoint(rest, 'clock', args);
  extra(rest, 1);
  const set = stringFlag(args, 'set');
  if (args.flags.has('set') && set === undefined) throw new UsageError('--set needs now or an ISO 8601 time');
  let date: Date | undefined;
  if (set !== undefined) {
    date = set === 'now' ? new Date() : new Date(set);
    if (!/^\d{4}-\d\d-\d\d/.test(set) && set !== 'now')
      throw new UsageError(`--set "${set}" is not now or an ISO 8601 time (e.g. 2024-05-01T12:00:00Z)`);
    if (Number.isNaN(date.getTime())) throw new UsageError(`--set "${set}" is not a valid time`);
    await checkControl(endpoint, args, io, `set the clock of ${endpointName(endpoint)}`);
  }
  const read = await run(endpoint, io, async (c) => {
    if (date) await c.setClock(set === 'now' ? new Date() : date, { signal: io.signal });
    return c.readClock({ signal: io.signal });
  });
  print(io, args, { clock: read }, () => [read.toISOString()]);
  return EXIT.OK;
}

export async function blocks(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = anyEndpoint(rest, 'blocks', args);
  extra(rest, 3);
  const typeText = rest[1]?.toUpperCase();
  if (typeText !== undefined && !Object.prototype.hasOwnProperty.call(BLOCK_TYPES, typeText)) {
    throw new UsageError(`unknown block type "${rest[1]}" (${Object.keys(BLOCK_TYPES).join(', ')})`);
  }
  const type = typeText as BlockType | undefined;
  const numberText = rest[2];
  if (numberText !== undefined && (!/^\d+$/.test(numberText) || Number(numberText) > 65535))
    throw new UsageError(`"${numberText}" is not a block number 0..65535`);
  const client = systemClient(endpoint, args);
  if (client instanceof S7Client) return s7Blocks(client, type, numberText, args, io);
  const { dataBlocks } = client;
  if (!dataBlocks) throw notOffered(endpoint, 'list blocks');
  if (numberText !== undefined) throw notOffered(endpoint, 'read block information');
  if (type !== undefined && type !== 'DB') throw notOffered(endpoint, `list ${type} blocks (only data blocks)`);
  const list = await withClient(client, io, async () => {
    const blocks = await dataBlocks.call(client, { signal: io.signal });
    return withAccess(blocks, client, io);
  });
  if (type === 'DB') {
    const numbers = list.map((b) => b.number);
    print(io, args, { type, numbers }, () => [numbers.length === 0 ? 'no DB blocks' : `DB: ${numbers.join(' ')}`]);
  } else {
    // The data blocks with their names and access: what S7CommPlus tells (no counts of code blocks).
    const access = (o: boolean | null) => (o === null ? 'access unknown' : o ? 'optimized' : 'standard');
    print(io, args, { DB: list }, () =>
      list.length === 0 ? ['no DB blocks'] : list.map((b) => `DB${b.number}  ${b.name}  ${access(b.optimized)}`),
    );
  }
  return EXIT.OK;
}

/**
 * Each data block with its access (optimized or standard), from the browse of
 * the blocks' type objects (the driver's browse port); null where it cannot
 * tell (no browse, or a PLC that gives no type information, as the s7commplus
 * emulator).
 */
async function withAccess(
  blocks: { number: number; name: string }[],
  client: AnyClient,
  io: CliIo,
): Promise<{ number: number; name: string; optimized: boolean | null }[]> {
  let table: SymbolTable | undefined;
  const browse = driverOf(client).browse;
  if (browse && blocks.length > 0) {
    try {
      table = await browse(client, { signal: io.signal });
    } catch (err) {
      if (io.signal.aborted) throw err;
      if (!(err instanceof PlcError) || isLinkError(err)) throw err;
    }
  }
  return blocks.map((b) => {
    const summary = table?.blocks.find((s) => s.db === b.number);
    return { number: b.number, name: b.name, optimized: summary ? summary.optimized === true : null };
  });
}

async function s7Blocks(
  client: S7Client,
  type: BlockType | undefined,
  numberText: string | undefined,
  args: ParsedArgs,
  io: CliIo,
): Promise<number> {
  const run = <R>(work: (c: S7Client) => Promise<R>) => withClient(client, io, () => work(client));
  if (type === undefined) {
    const counts = await run((c) => c.listBlocks({ signal: io.signal }));
    print(io, args, counts, () => Object.entries(counts).map(([t, n]) => `${t}: ${n}`));
  } else if (numberText === undefined) {
    const numbers = await run((c) => c.listBlocksOfType(type, { signal: io.signal }));
    print(io, args, { type, numbers }, () => [numbers.length === 0 ? `no ${type} blocks` : `${type}: ${numbers.join(' ')}`]);
  } else {
    const info = await run((c) => c.blockInfo(type, Number(numberText), { signal: io.signal }));
    print(io, args, info, () => Object.entries(info).map(([k, v]) => `${k}: ${typeof v === 'string' ? v : valueToText(v)}`));
  }
  return EXIT.OK;
}

const CPU_ACTIONS = Object.freeze({ stop: 'stop', start: 'hotStart', 'cold-start': 'coldStart' } as const);

export async function cpu(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = s7Endpoint(rest, 'cpu', args);
  const action = rest[1];
  if (action === undefined || !Object.prototype.hasOwnProperty.call(CPU_ACTIONS, action))
    throw new UsageError('cpu needs stop, start or cold-start');
  extra(rest, 2);
  const method = CPU_ACTIONS[action as keyof typeof CPU_ACTIONS];
  await checkControl(endpoint, args, io, `${action} the CPU at ${endpointName(endpoint)}`);
  const state = await run(endpoint, io, async (c) => {
    await c[method]({ signal: io.signal });
    return c.cpuState({ signal: io.signal });
  });
  print(io, args, { state: state.mode }, () => [`the CPU is in ${state.mode}`]);
  return EXIT.OK;
}

/** A failed step's exit code: an address or a name is a tag error (1), anything before it a connection error (3). */
function doctorExit(step: DoctorStep): number {
  return step.step.startsWith('address ') || step.step.startsWith('symbol ') ? EXIT.TAG_ERROR : EXIT.CONNECTION;
}

export async function doctor(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const url = rest[0];
  if (url === undefined) throw new UsageError('doctor needs a PLC url');
  // A URL that does not parse is a usage error, as for every command; the doctor itself starts at the name.
  const endpoint = parseUrl(url);
  if (!driverOf(endpoint).diagnose) {
    const schemes = schemesOffering('diagnose');
    throw new UsageError(`doctor checks ${schemes} connections: give an ${schemes} URL`);
  }
  // The password of an s7plus:// URL (PLCWIRE_PASSWORD, --password-file): to the client only, never in a step.
  const password = passwordOption(endpoint, args);
  const json = args.flags.has('json');
  const timeout = args.flags.has('timeout') ? intFlag(args, 'timeout', 20_000, 1, 600_000) : undefined;
  // Names resolve through --symbols (with --db, --strict-symbols) as they do for read: the same parsing, the same table.
  const { options: named } = symbolOptions(args);
  const onStep = json
    ? undefined
    : (s: DoctorStep) => {
        io.stdout.write(`${s.ok ? 'ok  ' : 'FAIL'} ${s.step}: ${s.detail}\n`);
        if (s.hint) io.stdout.write(`     fix: ${s.hint}\n`);
      };
  const report = await diagnose(url, rest.slice(1), {
    signal: io.signal,
    ...named,
    ...password,
    ...(timeout !== undefined ? { timeout } : {}),
    ...(onStep ? { onStep } : {}),
  });
  if (json) io.stdout.write(`${toJson(report)}\n`);
  const failed = report.steps.find((s) => !s.ok);
  return failed ? doctorExit(failed) : EXIT.OK;
}
