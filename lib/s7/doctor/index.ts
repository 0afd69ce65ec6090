/**
 * The connection doctor: walks an S7 connection step by step (name, TCP,
 * COTP, setup communication, identity, protection, PUT/GET, then each given
 * address) and stops at the first failure with what to change, in words.
 * The handshake steps run on a raw socket with the codec, so each answer
 * (a COTP disconnect and its reason, silence, a foreign protocol) can be
 * told apart; the steps after it use an S7Client. Every socket is closed on
 * every path, and the whole walk has one deadline.
 */
import { lookup } from 'node:dns/promises';
import * as net from 'node:net';
import { abortError, PlcError, toPlcError } from '../../errors';
import { FrameReader } from '../../link/framer';
import { openTcp } from '../../link/tcp';
import { parseUrl, type S7Endpoint } from '../../url';
import { S7_CPU_PRESETS, type S7CpuPreset } from '../presets';
import { valueToText } from '../../values/text';
import { S7Client } from '../client';
import { TagSteps, type Family, type StepContext } from './tags';
import type { SymbolTable } from '../../symbols/model';
import { checkTpkt, decodeCotp, decodeS7, encodeConnectionRequest, encodeSetupCommunication } from '../codec';
import { headerError } from '../constants';
import { localTsapFor, remoteTsapFor } from '../tsap';
import type { PlcInfo } from '../client';
import { hex4 } from '../../values/text';

/** One step's outcome: `step` names it (`tcp`, `cotp` …, `address DB1,INT0`), `hint` says what to change. */
export interface DoctorStep {
  step: string;
  ok: boolean;
  detail: string;
  hint?: string;
}

export interface DoctorReport {
  /** Every step passed. */
  ok: boolean;
  steps: DoctorStep[];
}

export interface DiagnoseOptions {
  /** The deadline of the whole walk in ms (default 20 s); each network step also keeps the URL's timeout. */
  timeout?: number;
  /** Aborting rejects with ABORTED once every socket is closed. */
  signal?: AbortSignal;
  /** Called with each step as soon as it is known. */
  onStep?: (step: DoctorStep) => void;
  /**
   * A compiled symbol table (compileSymbols), as connect(url, { symbols })
   * takes it: each given text that is not an S7 address is then a name,
   * resolved as a read resolves it and read at its address; an unknown name
   * is a failed step with the closest names the table has.
   */
  symbols?: SymbolTable;
  /** Names in a DB whose length in the PLC differs from the sources' are refused, as with ClientOptions.strictSymbols. */
  strictSymbols?: boolean;
}

const DEFAULT_DEADLINE = 20_000;
/** What the client asks for in the handshake (client/session.ts): TPDU 1024, 8 parallel jobs. */
const TPDU_SIZE_CODE = 0x0a;
const REQUESTED_AMQ = 8;
const MAX_FRAME = 0x10000 + 16;
/** COTP disconnect reason 1: congestion at the TSAP (ISO 8073 §13.5.3): the CPU's connections are all in use. */
const DR_CONGESTION = 1;
/** Header errors by which an S7-1200/1500 refuses Read Var without PUT/GET (SERVICE_ERRORS, HEADER_ERRORS). */
const PUT_GET_REFUSALS = [0x8104, 0x8304];
const PASSWORD_NEEDED = 0xd241;

const PUT_GET_HINT =
  'Allow PUT/GET in the CPU: TIA Portal → the CPU\'s Properties → Protection & Security → Connection mechanisms → tick "Permit access with PUT/GET communication from remote partner", then download the hardware configuration.';

/** How a CPU family is reached, from the connection presets (url.ts S7_CPU_PRESETS). */
function usualAddressing(): string {
  const p = S7_CPU_PRESETS;
  const rs = (k: S7CpuPreset) => `rack ${p[k].rack}, slot ${p[k].slot}`;
  const ts = (k: S7CpuPreset) => `localTsap=${hex4(p[k].localTsap!)}&remoteTsap=${hex4(p[k].remoteTsap!)}`;
  return (
    `Usual values: S7-300 ${rs('s7-300')}; S7-400 ${rs('s7-400')} (or the slot the CPU sits in); S7-1200/1500 ${rs('s7-1200')} (or slot 0); ` +
    `S7-200 with a CP 243-1 ${ts('s7-200')} (as set in the Ethernet wizard); LOGO! ${ts('logo')} (as set in LOGO!Soft Comfort).`
  );
}

/** What a connection request tries: rack/slot, or a TSAP pair. */
interface Addressing {
  callingTsap: number;
  calledTsap: number;
  /** How to say it in a URL query. */
  query: string;
  /** How to say it in words. */
  label: string;
  /** The family this addressing points to when the CPU accepts it. */
  family: string;
}

function addressingOf(e: S7Endpoint): Addressing {
  if (e.remoteTsap !== undefined) {
    return tsapPair(e.localTsap!, e.remoteTsap, '');
  }
  return {
    callingTsap: localTsapFor(e.connectionType),
    calledTsap: remoteTsapFor(e.connectionType, e.rack, e.slot),
    query: `rack=${e.rack}&slot=${e.slot}`,
    label: `rack ${e.rack}, slot ${e.slot}`,
    family: '',
  };
}

function tsapPair(local: number, remote: number, family: string): Addressing {
  return {
    callingTsap: local,
    calledTsap: remote,
    query: `localTsap=${hex4(local)}&remoteTsap=${hex4(remote)}`,
    label: `local TSAP 0x${hex4(local)}, remote TSAP 0x${hex4(remote)}`,
    family,
  };
}

/** The addressings tried when the URL's is refused: the usual slots first (a rack/slot CPU accepts a foreign TSAP too), then the TSAP pairs. */
function alternatives(e: S7Endpoint): Addressing[] {
  const slot = (s: number, family: string): Addressing => ({
    callingTsap: localTsapFor(e.connectionType),
    calledTsap: remoteTsapFor(e.connectionType, 0, s),
    query: `rack=0&slot=${s}`,
    label: `rack 0, slot ${s}`,
    family,
  });
  const pair = (k: 's7-200' | 'logo', family: string): Addressing => {
    const { localTsap, remoteTsap } = S7_CPU_PRESETS[k];
    return tsapPair(localTsap!, remoteTsap!, family);
  };
  const tried = addressingOf(e);
  return [
    slot(1, 'an S7-1200/1500 (or ET 200SP CPU)'),
    slot(2, 'an S7-300 (or an S7-400 in slot 2)'),
    slot(3, 'an S7-400'),
    slot(0, 'an S7-1200/1500'),
    pair('s7-200', 'an S7-200 with a CP 243-1'),
    pair('logo', 'a LOGO!'),
  ].filter((a) => a.calledTsap !== tried.calledTsap || a.callingTsap !== tried.callingTsap);
}

/** The family an order code (MLFB) or module type names; undefined when it is not one we know. */
export function familyOf(info: Pick<PlcInfo, 'orderCode' | 'moduleTypeName'>): Family | undefined {
  const code = (info.orderCode ?? '').replace(/\s+/g, '').toUpperCase();
  if (/^6ES721\d-1/.test(code)) return 'S7-1200';
  if (/^6ES721\d-/.test(code)) return 'S7-200';
  if (/^6ES751\d-/.test(code)) return 'S7-1500';
  if (/^6ES731\d-/.test(code)) return 'S7-300';
  if (/^6ES741\d-/.test(code)) return 'S7-400';
  if (/^6ED1052-/.test(code)) return 'LOGO!';
  const name = info.moduleTypeName ?? '';
  if (/CPU\s*12\d\d/.test(name)) return 'S7-1200';
  if (/CPU\s*15\d\d/.test(name)) return 'S7-1500';
  if (/CPU\s*3\d\d/.test(name)) return 'S7-300';
  if (/CPU\s*4\d\d/.test(name)) return 'S7-400';
  if (/LOGO/i.test(name)) return 'LOGO!';
  return undefined;
}

/**
 * Diagnoses the connection to an S7 PLC. Resolves a report whose steps end
 * at the first failure (every step up to it passed); rejects only with
 * ABORTED when `options.signal` aborts. Nothing is written to the PLC.
 */
export async function diagnose(url: string, addresses: readonly string[] = [], options: DiagnoseOptions = {}): Promise<DoctorReport> {
  const doctor = new Doctor(options);
  try {
    await doctor.run(url, addresses);
  } finally {
    await doctor.dispose();
  }
  return doctor.report();
}

/** Thrown inside the walk to end it at a failed step. */
class Stop extends Error {}

class Doctor {
  private readonly steps: DoctorStep[] = [];
  private readonly ctl = new AbortController();
  private readonly deadline: number;
  private readonly timer: NodeJS.Timeout;
  private readonly sockets = new Set<net.Socket>();
  private client: S7Client | undefined;
  private readonly onUserAbort = () => this.ctl.abort();

  constructor(private readonly options: DiagnoseOptions) {
    const ms = options.timeout ?? DEFAULT_DEADLINE;
    if (!Number.isFinite(ms) || ms <= 0)
      throw new PlcError('INVALID_VALUE', `diagnose: timeout must be a positive number of ms, got ${String(ms)}`);
    this.deadline = Date.now() + ms;
    this.timer = setTimeout(() => this.ctl.abort(), ms);
    if (options.signal?.aborted) this.ctl.abort();
    else options.signal?.addEventListener('abort', this.onUserAbort, { once: true });
  }

  report(): DoctorReport {
    return { ok: this.steps.length > 0 && this.steps.every((s) => s.ok), steps: this.steps };
  }

  async dispose(): Promise<void> {
    clearTimeout(this.timer);
    this.options.signal?.removeEventListener('abort', this.onUserAbort);
    for (const s of this.sockets) s.destroy();
    this.sockets.clear();
    await this.client?.close();
  }

  private get signal(): AbortSignal {
    return this.ctl.signal;
  }

  /** Per network step: the URL's timeout, cut to what is left of the deadline. */
  private stepTimeout(e: S7Endpoint): number {
    return Math.max(1, Math.min(e.timeout, this.deadline - Date.now()));
  }

  /** What the tag steps (tags.ts) use of this walk. */
  private context(): StepContext {
    return {
      client: this.client!,
      signal: this.signal,
      pass: (step, detail, hint) => this.pass(step, detail, hint),
      fail: (step, detail, hint) => this.fail(step, detail, hint),
      failed: (step, err, other) => this.failed(step, err, other),
    };
  }

  private record(step: DoctorStep): void {
    const s: DoctorStep = { step: step.step, ok: step.ok, detail: step.detail };
    if (step.hint !== undefined) s.hint = step.hint;
    this.steps.push(s);
    this.options.onStep?.(s);
  }

  private pass(step: string, detail: string, hint?: string): void {
    this.record({ step, ok: true, detail, ...(hint !== undefined ? { hint } : {}) });
  }

  private fail(step: string, detail: string, hint?: string): never {
    this.record({ step, ok: false, detail, ...(hint !== undefined ? { hint } : {}) });
    throw new Stop();
  }

  /** An error inside a step: an abort by the caller ends the walk, the deadline fails the step, anything else is `other`. */
  private failed(step: string, err: unknown, other: (e: PlcError) => never): never {
    if (err instanceof Stop) throw err;
    if (this.options.signal?.aborted) throw abortError('the connection doctor', this.options.signal);
    if (this.signal.aborted) {
      this.fail(
        step,
        `no result before the doctor's deadline of ${this.options.timeout ?? DEFAULT_DEADLINE} ms`,
        "Give the doctor more time (the timeout option, or --timeout), or raise the URL's timeout on a slow link.",
      );
    }
    return other(toPlcError(err, 'CONNECT_FAILED'));
  }

  async run(url: string, addresses: readonly string[]): Promise<void> {
    try {
      const e = this.url(url);
      const address = await this.resolve(e);
      await this.handshake(e, address);
      const info = await this.identity(e);
      this.protection(info);
      const family = info.family;
      await this.putGet(family);
      const tags = new TagSteps(this.context(), family, this.options.symbols);
      for (const a of addresses) await tags.check(a);
    } catch (err) {
      if (err instanceof Stop) return;
      if (this.options.signal?.aborted) throw abortError('the connection doctor', this.options.signal);
      // The deadline ran out where no step caught it (between steps, or inside one's own retries): a failed step, not a rejection.
      if (this.signal.aborted) {
        const after = this.steps.at(-1)?.step;
        this.record({
          step: 'deadline',
          ok: false,
          detail: `no result before the doctor's deadline of ${this.options.timeout ?? DEFAULT_DEADLINE} ms${after ? ` (after the ${after} step)` : ''}`,
          hint: "Give the doctor more time (the timeout option, or --timeout), or raise the URL's timeout on a slow link.",
        });
        return;
      }
      throw err;
    }
  }

  // ---------------------------------------------------------------- steps

  private url(url: string): S7Endpoint {
    let e;
    try {
      e = parseUrl(url);
    } catch (err) {
      this.fail('url', (err as Error).message, 'Write the URL as s7://<host>[:port]?rack=0&slot=1 (README, "URLs").');
    }
    if (e.protocol !== 's7') this.fail('url', `the doctor checks S7 connections; this URL is ${e.protocol}`, 'Give an s7:// URL.');
    return e;
  }

  private async resolve(e: S7Endpoint): Promise<string> {
    const host = e.host.replace(/^\[|\]$/g, '');
    if (net.isIP(host)) {
      this.pass('resolve', `${host} is an IP address`);
      return host;
    }
    try {
      const { address } = await this.race(lookup(host), e);
      this.pass('resolve', `${host} resolves to ${address}`);
      return address;
    } catch (err) {
      return this.failed('resolve', err, (p) => {
        const code = (p.cause as NodeJS.ErrnoException | undefined)?.code ?? (err as NodeJS.ErrnoException).code;
        if (code === 'EAI_AGAIN')
          this.fail(
            'resolve',
            `"${host}" could not be looked up (EAI_AGAIN): no DNS server answered`,
            "Check this machine's DNS settings, or use the PLC's IP address in the URL.",
          );
        this.fail(
          'resolve',
          `"${host}" does not resolve${code ? ` (${code})` : ''}`,
          "Check the spelling of the host name, or use the PLC's IP address in the URL (TIA Portal: the CPU's Properties → PROFINET interface → Ethernet addresses).",
        );
      });
    }
  }

  /** A promise that cannot be aborted (a DNS lookup), raced with the deadline and the caller's abort. */
  private race<T>(p: Promise<T>, e: S7Endpoint): Promise<T> {
    return new Promise<T>((resolve, reject) => {
      const ms = this.stepTimeout(e);
      const done = () => {
        clearTimeout(timer);
        this.signal.removeEventListener('abort', onAbort);
      };
      const onAbort = () => {
        done();
        reject(abortError('a lookup', this.signal));
      };
      const timer = setTimeout(() => {
        done();
        reject(new PlcError('TIMEOUT', `no answer within ${ms} ms`));
      }, ms);
      if (this.signal.aborted) return onAbort();
      this.signal.addEventListener('abort', onAbort, { once: true });
      p.then(
        (v) => (done(), resolve(v)),
        (err: unknown) => (done(), reject(err)),
      );
    });
  }

  private async tcp(e: S7Endpoint, address: string): Promise<net.Socket> {
    const socket = await openTcp({ host: address, port: e.port, timeout: this.stepTimeout(e), signal: this.signal, keepAliveMs: 0 });
    this.sockets.add(socket);
    socket.on('error', () => undefined);
    socket.once('close', () => this.sockets.delete(socket));
    return socket;
  }

  private async handshake(e: S7Endpoint, address: string): Promise<void> {
    const where = `${address}:${e.port}`;
    let socket: net.Socket;
    try {
      socket = await this.tcp(e, address);
    } catch (err) {
      return this.failed('tcp', err, (p) => this.tcpFailure(e, where, p));
    }
    this.pass('tcp', `${where} accepts TCP connections`);
    try {
      const tried = addressingOf(e);
      const answer = await this.connectionRequest(socket, tried, e);
      if (answer.kind !== 'accepted') await this.cotpFailure(e, address, tried, answer);
      this.pass(
        'cotp',
        `the CPU accepted the connection request (${tried.label}: called TSAP 0x${hex4(tried.calledTsap)}, calling TSAP 0x${hex4(tried.callingTsap)})`,
      );
      await this.setup(socket, e);
    } finally {
      socket.destroy();
    }
  }

  private tcpFailure(e: S7Endpoint, where: string, p: PlcError): never {
    const code = (p.cause as NodeJS.ErrnoException | undefined)?.code;
    if (p.code === 'TIMEOUT') {
      this.fail(
        'tcp',
        `no answer from ${where} within ${this.stepTimeout(e)} ms: filtered (the connection attempt got no reply at all)`,
        'The PLC is off or unplugged, in another subnet without a route, or a firewall drops port ' +
          `${e.port}. Check that this machine is in the PLC's subnet (e.g. 192.168.0.x/24 for 192.168.0.1), that the PLC answers ping, and any firewall between.`,
      );
    }
    if (code === 'ECONNREFUSED') {
      this.fail(
        'tcp',
        `${where} refused the connection (ECONNREFUSED): the host is up, but nothing listens on port ${e.port}`,
        `Check that the address is the PLC's (not a PC's or an HMI's) and the port: S7 uses 102; a gateway or simulator may use another (add :port to the URL).`,
      );
    }
    if (code === 'EHOSTUNREACH' || code === 'ENETUNREACH') {
      this.fail('tcp', `no route to ${where} (${code})`, "Check the IP address, this machine's subnet and gateway, and the cable.");
    }
    this.fail('tcp', p.message);
  }

  /** Sends a COTP connection request and waits for the answer frame. */
  private async connectionRequest(socket: net.Socket, a: Addressing, e: S7Endpoint): Promise<CotpAnswer> {
    const frames = new FrameWaiter(socket, this.signal);
    try {
      socket.write(
        encodeConnectionRequest({ sourceRef: 0x0001, callingTsap: a.callingTsap, calledTsap: a.calledTsap, tpduSize: TPDU_SIZE_CODE }),
      );
      const frame = await frames.next(this.stepTimeout(e));
      if (frame.kind !== 'frame') return frame;
      const m = decodeCotp(frame.frame);
      if (m.type === 'CC') return { kind: 'accepted' };
      if (m.type === 'DR') return { kind: 'refused', reason: m.reason };
      return { kind: 'foreign', message: `a COTP ${m.type} instead of a connection confirm` };
    } catch (err) {
      if (this.signal.aborted) throw err;
      return { kind: 'foreign', message: (err as Error).message };
    } finally {
      frames.stop();
    }
  }

  private async cotpFailure(
    e: S7Endpoint,
    address: string,
    tried: Addressing,
    answer: Exclude<CotpAnswer, { kind: 'accepted' }>,
  ): Promise<never> {
    const asked = (why: string) =>
      `${tried.label} (called TSAP 0x${hex4(tried.calledTsap)}, calling TSAP 0x${hex4(tried.callingTsap)}; ${why})`;
    if (answer.kind === 'silent') {
      this.fail(
        'cotp',
        `port ${e.port} accepts TCP but nothing answered the ISO-on-TCP connection request within ${answer.ms} ms`,
        'This is probably not an S7 PLC (another device or service on that address and port), or a communication processor that hangs: check the address, and power-cycle the CP.',
      );
    }
    if (answer.kind === 'foreign') {
      this.fail(
        'cotp',
        `the answer is not an ISO-on-TCP connection confirm: ${answer.message}`,
        'Another protocol listens on this port: check the address and the port (S7 uses 102).',
      );
    }
    if (answer.kind === 'refused' && answer.reason === DR_CONGESTION) {
      this.fail(
        'cotp',
        `the CPU refused the connection request for ${asked('COTP disconnect, reason 1: congestion')}: no free connection`,
        'All connections of the CPU are in use: close other clients (HMI, SCADA, TIA Portal online, other scripts) or give the CPU more connection resources in its hardware configuration.',
      );
    }
    const how = answer.kind === 'refused' ? `COTP disconnect, reason ${answer.reason}` : 'it closed the connection without an answer';
    const found = await this.findAddressing(e, address);
    const fix = found
      ? `The CPU accepts ${found.label}, which points to ${found.family}: use ?${found.query} in the URL. `
      : 'None of the usual rack/slot or TSAP values was accepted either. ';
    this.fail('cotp', `the CPU refused the connection request for ${asked(how)}: wrong rack/slot or TSAP`, `${fix}${usualAddressing()}`);
  }

  /** Tries the usual addressings, one connection each (closed at once), until one is accepted. */
  private async findAddressing(e: S7Endpoint, address: string): Promise<Addressing | undefined> {
    for (const a of alternatives(e)) {
      if (this.signal.aborted) return undefined;
      let socket: net.Socket | undefined;
      try {
        socket = await this.tcp(e, address);
        if ((await this.connectionRequest(socket, a, e)).kind === 'accepted') return a;
      } catch {
        if (this.signal.aborted) return undefined;
      } finally {
        socket?.destroy();
      }
    }
    return undefined;
  }

  private async setup(socket: net.Socket, e: S7Endpoint): Promise<void> {
    const frames = new FrameWaiter(socket, this.signal);
    try {
      socket.write(encodeSetupCommunication(0, { maxAmqCalling: REQUESTED_AMQ, maxAmqCalled: REQUESTED_AMQ, pduSize: e.pduSize }));
      const answer = await frames.next(this.stepTimeout(e));
      if (answer.kind === 'silent')
        this.fail(
          'setup',
          `no answer to setup communication within ${answer.ms} ms`,
          'The CPU accepted the connection but does not talk S7: check that the rack/slot or TSAP names the CPU (not a CP or a module without S7 communication).',
        );
      if (answer.kind === 'closed')
        this.fail(
          'setup',
          'the CPU closed the connection at setup communication',
          "The CPU accepted the connection but not the S7 session: check rack/slot or TSAP, and the CPU's connection resources.",
        );
      if (answer.kind === 'foreign') this.fail('setup', `the answer to setup communication is malformed: ${answer.message}`);
      const ack = decodeS7(answer.frame);
      if (ack.kind === 'error') {
        const err = headerError(ack.errorClass, ack.errorCode, 'setup communication');
        this.fail(
          'setup',
          err.message,
          "The CPU refuses the S7 session: check the PDU size asked for (the pdu URL parameter) and the CPU's connection settings.",
        );
      }
      if (ack.kind !== 'setup-ack') this.fail('setup', `the answer to setup communication is a ${ack.kind}`);
      const { pduSize, maxAmqCalling, maxAmqCalled } = ack.params;
      if (pduSize < 64) this.fail('setup', `the CPU negotiated an unusable PDU size of ${pduSize} bytes`);
      const amq = Math.max(1, Math.min(maxAmqCalling, maxAmqCalled, REQUESTED_AMQ));
      this.pass('setup', `PDU ${pduSize} bytes (asked ${e.pduSize}), ${amq} parallel job${amq === 1 ? '' : 's'} (AmQ)`);
    } catch (err) {
      return this.failed('setup', err, (p) => this.fail('setup', p.message));
    } finally {
      frames.stop();
    }
  }

  private async identity(e: S7Endpoint): Promise<PlcInfo & { family: Family | undefined }> {
    const { symbols, strictSymbols } = this.options;
    const client = new S7Client(
      { ...e, timeout: this.stepTimeout(e) },
      symbols ? { symbols, ...(strictSymbols ? { strictSymbols } : {}) } : {},
    );
    this.client = client;
    client.on('error', () => undefined);
    const onAbort = () => void client.close();
    this.signal.addEventListener('abort', onAbort, { once: true });
    try {
      await client.connect();
      const info = await client.info({ signal: this.signal });
      const family = familyOf(info);
      const who = [info.moduleTypeName, info.orderCode && `(${info.orderCode})`, info.firmware && `firmware ${info.firmware}`]
        .filter(Boolean)
        .join(' ');
      const names = [
        info.asName && `station "${info.asName}"`,
        info.moduleName && `module "${info.moduleName}"`,
        info.serialNumber && `serial ${info.serialNumber}`,
      ]
        .filter(Boolean)
        .join(', ');
      const state = info.state ? `in ${info.state}` : 'state not reported';
      const detail = `${who || 'the CPU does not say what it is (no identity lists)'}${names ? `; ${names}` : ''}; ${state}${family ? `; family ${family}` : ''}`;
      const hint =
        info.state === 'STOP'
          ? 'The CPU is in STOP: memory can be read and written, but the program does not run (values do not change). Look at the diagnostic buffer (plcwire diag) for why it stopped.'
          : undefined;
      this.pass('identity', detail, hint);
      return { ...info, family };
    } catch (err) {
      return this.failed('identity', err, (p) =>
        this.fail(
          'identity',
          p.message,
          'The handshake works but the S7 connection does not: run the doctor again; if it repeats, report it with this output.',
        ),
      );
    } finally {
      this.signal.removeEventListener('abort', onAbort);
    }
  }

  private protection(info: PlcInfo & { family: Family | undefined }): void {
    const p = info.protection;
    const modern = info.family === 'S7-1200' || info.family === 'S7-1500';
    if (!p) return this.pass('protection', 'the CPU does not report its protection level (SZL 0x0232)');
    if (p.level <= 1)
      return this.pass('protection', `level ${p.level}: no protection${p.keySwitch ? ` (mode selector ${p.keySwitch})` : ''}`);
    const where = modern
      ? 'TIA Portal → the CPU\'s Properties → Protection & Security → Access level ("Full access" for writes)'
      : "the CPU's protection settings in the hardware configuration, or the mode selector";
    if (p.level === 2) {
      return this.pass(
        'protection',
        `level 2: write protection${p.keySwitch ? ` (mode selector ${p.keySwitch})` : ''}: reads work; writes, stop/start and setting the clock need the password`,
        `To write, give the password on the connection (S7Client.setPassword) or lower the protection: ${where}.`,
      );
    }
    this.fail(
      'protection',
      `level ${p.level}: read/write protection: the CPU refuses reads of its data without the password`,
      `Give the password on the connection (S7Client.setPassword) or lower the protection: ${where}.`,
    );
  }

  private async putGet(family: Family | undefined): Promise<void> {
    const client = this.client!;
    const probe = 'MB0';
    try {
      const r = (await client.readDetailed([probe], { signal: this.signal }))[probe]!;
      const needs = family === 'S7-1200' || family === 'S7-1500' ? '' : family ? `; an ${family} needs no setting for it` : '';
      if (r.ok) return this.pass('putget', `the CPU serves Read Var (PUT/GET${needs}): ${probe} = ${valueToText(r.value)}`);
      const e = r.error;
      if (e.plcCode !== undefined && PUT_GET_REFUSALS.includes(e.plcCode)) {
        this.fail('putget', `the CPU refuses Read Var as a whole: ${e.message}`, PUT_GET_HINT);
      }
      if (e.plcCode === PASSWORD_NEEDED)
        this.fail(
          'putget',
          `the CPU refuses Read Var: ${e.message}`,
          'The protection level forbids reads: give the password (S7Client.setPassword) or lower the protection.',
        );
      if (e.code === 'CONNECTION_LOST' || e.code === 'TIMEOUT' || e.code === 'NOT_CONNECTED') this.fail('putget', e.message);
      // An answer per item (MB0 out of range on a CPU without flags) still means Read Var is served.
      this.pass('putget', `the CPU serves Read Var (PUT/GET${needs}); ${probe}: ${e.message}`);
    } catch (err) {
      return this.failed('putget', err, (p) => this.fail('putget', p.message));
    }
  }
}

type CotpAnswer =
  | { kind: 'accepted' }
  | { kind: 'refused'; reason: number }
  | { kind: 'closed' }
  | { kind: 'silent'; ms: number }
  | { kind: 'foreign'; message: string };
type FrameResult =
  { kind: 'frame'; frame: Buffer } | { kind: 'closed' } | { kind: 'silent'; ms: number } | { kind: 'foreign'; message: string };

/** Whole TPKT frames from a raw socket, one at a time, each with its own wait. */
class FrameWaiter {
  private readonly reader = new FrameReader(checkTpkt, MAX_FRAME);
  private readonly frames: Buffer[] = [];
  private end: FrameResult | undefined;
  private wake: (() => void) | undefined;
  private readonly onData = (chunk: Buffer) => {
    try {
      this.frames.push(...this.reader.push(chunk));
    } catch (err) {
      this.end ??= { kind: 'foreign', message: (err as Error).message };
    }
    this.wake?.();
  };
  private readonly onClose = () => {
    this.end ??= { kind: 'closed' };
    this.wake?.();
  };

  constructor(
    private readonly socket: net.Socket,
    private readonly signal: AbortSignal,
  ) {
    socket.on('data', this.onData);
    socket.on('close', this.onClose);
    if (socket.destroyed) this.end = { kind: 'closed' };
  }

  next(ms: number): Promise<FrameResult> {
    return new Promise((resolve, reject) => {
      const done = () => {
        clearTimeout(timer);
        this.wake = undefined;
        this.signal.removeEventListener('abort', onAbort);
      };
      const check = () => {
        const frame = this.frames.shift();
        if (frame) return (done(), resolve({ kind: 'frame', frame }), true);
        if (this.end) return (done(), resolve(this.end), true);
        return false;
      };
      const onAbort = () => (done(), reject(abortError('waiting for a frame', this.signal)));
      const timer = setTimeout(() => (done(), resolve({ kind: 'silent', ms })), ms);
      if (check()) return;
      if (this.signal.aborted) return onAbort();
      this.signal.addEventListener('abort', onAbort, { once: true });
      this.wake = () => void check();
    });
  }

  stop(): void {
    this.socket.removeListener('data', this.onData);
    this.socket.removeListener('close', this.onClose);
  }
}
