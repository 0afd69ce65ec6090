/**
 * The connection doctor's S7 steps: an S7 connection step by step (name, TCP,
 * COTP, setup communication, identity, protection, PUT/GET, then each given
 * address), run inside the walk of lib/doctor/ (which stops at the first
 * failure), each failure with what to change, in words.
 * The handshake steps are the client's own (handshake.ts reads their answers
 * in the doctor's words); the steps after it use an S7Client, the address and name steps in tags.ts. What
 * a step says to change is in hints.ts, the CPU families and their usual
 * addressing in families.ts. Every socket is closed on every path, and the
 * whole walk has one deadline.
 */
import { lookup } from 'node:dns/promises';
import * as net from 'node:net';
import { abortError, PlcError } from '../../errors';
import { openTcp } from '../../link/tcp';
import type { DiagnosePort, DoctorSteps } from '../../doctor-steps';
import { valueToText } from '../../values/text';
import { S7Client } from '../client';
import { TagSteps, type StepContext } from './tags';
import type { PlcInfo } from '../client';
import { familyOf, type Family } from './families';
import { Handshake, type HandshakeContext } from './handshake';
import { HINT } from './hints';
import type { S7Endpoint } from '../url';

export { familyOf } from './families';

/** Header errors by which an S7-1200/1500 refuses Read Var without PUT/GET (SERVICE_ERRORS, HEADER_ERRORS). */
const PUT_GET_REFUSALS = [0x8104, 0x8304];
const PASSWORD_NEEDED = 0xd241;

/**
 * The S7 doctor as the registry's diagnose port (lib/drivers.ts): the steps
 * of an S7 connection, run inside the walk of lib/doctor/ once it parsed the
 * URL. Nothing is written to the PLC; every socket is closed before it returns.
 */
export const S7_DOCTOR: DiagnosePort<S7Endpoint> = Object.freeze({
  urlHint: HINT.url,
  async run(endpoint: S7Endpoint, addresses: readonly string[], steps: DoctorSteps): Promise<void> {
    const doctor = new Doctor(steps);
    try {
      await doctor.run(endpoint, addresses);
    } finally {
      await doctor.dispose();
    }
  },
});

class Doctor {
  private readonly deadline: number;
  private readonly sockets = new Set<net.Socket>();
  private client: S7Client | undefined;

  constructor(private readonly w: DoctorSteps) {
    this.deadline = Date.now() + w.ms;
  }

  async dispose(): Promise<void> {
    for (const s of this.sockets) s.destroy();
    this.sockets.clear();
    await this.client?.close();
  }

  /** Per network step: the URL's timeout, cut to what is left of the deadline. */
  private stepTimeout(e: S7Endpoint): number {
    return Math.max(1, Math.min(e.timeout, this.deadline - Date.now()));
  }

  /** What the tag steps (tags.ts) use of this walk. */
  private context(): StepContext {
    return {
      client: this.client!,
      signal: this.w.signal,
      pass: (step, detail, hint) => this.w.pass(step, detail, hint),
      fail: (step, detail, hint) => this.w.fail(step, detail, hint),
      failed: (step, err, other) => this.w.failed(step, err, other),
    };
  }

  /** What the handshake steps (handshake.ts) use of this walk. */
  private handshakeContext(): HandshakeContext {
    return {
      signal: this.w.signal,
      pass: (step, detail, hint) => this.w.pass(step, detail, hint),
      fail: (step, detail, hint) => this.w.fail(step, detail, hint),
      failed: (step, err, other) => this.w.failed(step, err, other),
      stepTimeout: (e) => this.stepTimeout(e),
      tcp: (e, address) => this.tcp(e, address),
    };
  }

  async run(e: S7Endpoint, addresses: readonly string[]): Promise<void> {
    const address = await this.resolve(e);
    await new Handshake(this.handshakeContext()).run(e, address);
    const info = await this.identity(e);
    this.protection(info);
    const family = info.family;
    await this.putGet(family);
    const tags = new TagSteps(this.context(), family, this.w.options.symbols);
    for (const a of addresses) await tags.check(a);
  }

  // ---------------------------------------------------------------- steps

  private async resolve(e: S7Endpoint): Promise<string> {
    const host = e.host.replace(/^\[|\]$/g, '');
    if (net.isIP(host)) {
      this.w.pass('resolve', `${host} is an IP address`);
      return host;
    }
    try {
      const { address } = await this.race(lookup(host), e);
      this.w.pass('resolve', `${host} resolves to ${address}`);
      return address;
    } catch (err) {
      return this.w.failed('resolve', err, (p) => {
        const code = (p.cause as NodeJS.ErrnoException | undefined)?.code ?? (err as NodeJS.ErrnoException).code;
        if (code === 'EAI_AGAIN')
          this.w.fail('resolve', `"${host}" could not be looked up (EAI_AGAIN): no DNS server answered`, HINT.noDns);
        this.w.fail('resolve', `"${host}" does not resolve${code ? ` (${code})` : ''}`, HINT.unknownHost);
      });
    }
  }

  /** A promise that cannot be aborted (a DNS lookup), raced with the deadline and the caller's abort. */
  private race<T>(p: Promise<T>, e: S7Endpoint): Promise<T> {
    return new Promise<T>((resolve, reject) => {
      const ms = this.stepTimeout(e);
      const done = () => {
        clearTimeout(timer);
        this.w.signal.removeEventListener('abort', onAbort);
      };
      const onAbort = () => {
        done();
        reject(abortError('a lookup', this.w.signal));
      };
      const timer = setTimeout(() => {
        done();
        reject(new PlcError('TIMEOUT', `no answer within ${ms} ms`));
      }, ms);
      if (this.w.signal.aborted) return onAbort();
      this.w.signal.addEventListener('abort', onAbort, { once: true });
      p.then(
        (v) => (done(), resolve(v)),
        (err: unknown) => (done(), reject(err)),
      );
    });
  }

  private async tcp(e: S7Endpoint, address: string): Promise<net.Socket> {
    const socket = await openTcp({ host: address, port: e.port, timeout: this.stepTimeout(e), signal: this.w.signal, keepAliveMs: 0 });
    this.sockets.add(socket);
    socket.on('error', () => undefined);
    socket.once('close', () => this.sockets.delete(socket));
    return socket;
  }

  private async identity(e: S7Endpoint): Promise<PlcInfo & { family: Family | undefined }> {
    const { symbols, strictSymbols } = this.w.options;
    const client = new S7Client(
      { ...e, timeout: this.stepTimeout(e) },
      symbols ? { symbols, ...(strictSymbols ? { strictSymbols } : {}) } : {},
    );
    this.client = client;
    client.on('error', () => undefined);
    const onAbort = () => void client.close();
    this.w.signal.addEventListener('abort', onAbort, { once: true });
    try {
      await client.connect();
      const info = await client.info({ signal: this.w.signal });
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
      const hint = info.state === 'STOP' ? HINT.inStop : undefined;
      this.w.pass('identity', detail, hint);
      return { ...info, family };
    } catch (err) {
      return this.w.failed('identity', err, (p) => this.w.fail('identity', p.message, HINT.noIdentity));
    } finally {
      this.w.signal.removeEventListener('abort', onAbort);
    }
  }

  private protection(info: PlcInfo & { family: Family | undefined }): void {
    const p = info.protection;
    const modern = info.family === 'S7-1200' || info.family === 'S7-1500';
    if (!p) return this.w.pass('protection', 'the CPU does not report its protection level (SZL 0x0232)');
    if (p.level <= 1)
      return this.w.pass('protection', `level ${p.level}: no protection${p.keySwitch ? ` (mode selector ${p.keySwitch})` : ''}`);
    if (p.level === 2) {
      return this.w.pass(
        'protection',
        `level 2: write protection${p.keySwitch ? ` (mode selector ${p.keySwitch})` : ''}: reads work; writes, stop/start and setting the clock need the password`,
        HINT.writeProtected(modern),
      );
    }
    this.w.fail(
      'protection',
      `level ${p.level}: read/write protection: the CPU refuses reads of its data without the password`,
      HINT.readProtected(modern),
    );
  }

  private async putGet(family: Family | undefined): Promise<void> {
    const client = this.client!;
    const probe = 'MB0';
    try {
      const r = (await client.readDetailed([probe], { signal: this.w.signal }))[probe]!;
      const needs = family === 'S7-1200' || family === 'S7-1500' ? '' : family ? `; an ${family} needs no setting for it` : '';
      if (r.ok) return this.w.pass('putget', `the CPU serves Read Var (PUT/GET${needs}): ${probe} = ${valueToText(r.value)}`);
      const e = r.error;
      if (e.plcCode !== undefined && PUT_GET_REFUSALS.includes(e.plcCode)) {
        this.w.fail('putget', `the CPU refuses Read Var as a whole: ${e.message}`, HINT.putGet);
      }
      if (e.plcCode === PASSWORD_NEEDED) this.w.fail('putget', `the CPU refuses Read Var: ${e.message}`, HINT.password);
      if (e.code === 'CONNECTION_LOST' || e.code === 'TIMEOUT' || e.code === 'NOT_CONNECTED') this.w.fail('putget', e.message);
      // An answer per item (MB0 out of range on a CPU without flags) still means Read Var is served.
      this.w.pass('putget', `the CPU serves Read Var (PUT/GET${needs}); ${probe}: ${e.message}`);
    } catch (err) {
      return this.w.failed('putget', err, (p) => this.w.fail('putget', p.message));
    }
  }
}
