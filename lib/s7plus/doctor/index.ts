/**
 * The connection doctor's steps of an s7plus:// URL: TCP → COTP (the
 * S7CommPlus TSAPs) → InitSSL → TLS (the PLC's certificate, and whether it
 * was pinned, signed by the given CA, or accepted unchecked) → session
 * (protocol version, session id) → password → identity → browse → each given
 * name or address, run inside the walk of lib/doctor/ (steps with ok,
 * detail and a hint in words, as the S7 doctor's). The handshake steps are the
 * client's own: openS7PlusSession tells each step that passed (OpenOptions
 * onStep), so a failure is the step after the last one told. Nothing is
 * written to the PLC; the one connection is closed on every path, and the
 * whole walk has one deadline.
 */
import { PlcError } from '../../errors';
import { IsoConnectError } from '../../iso/connect';
import { openTcp } from '../../link/tcp';
import { S7_TAG_SYNTAX } from '../../address';
import { NETWORK_HINT } from '../../iso/hints';
import type { DiagnosePort, DoctorSteps } from '../../doctor-steps';
import type { SymbolTable } from '../../symbols/model';
import { realsShown } from '../../symbols/reals';
import { textOf } from '../../values/text';
import { S7PlusClient } from '../client';
import type { HandshakeStep } from '../client/handshake';
import { CertificateError } from '../transport/trust';
import type { S7PlusEndpoint } from '../url';
import { PLUS_HINT } from './hints';

/**
 * The S7CommPlus doctor as the registry's diagnose port (lib/drivers.ts): the
 * steps of a connection to an S7-1200/1500, run inside the walk of lib/doctor/
 * once it parsed the URL. `options.password` (legitimation) is never in a
 * step, a hint or the report; the one connection is closed before it returns.
 */
export const S7PLUS_DOCTOR: DiagnosePort<S7PlusEndpoint> = Object.freeze({
  urlHint: PLUS_HINT.url,
  async run(
    endpoint: S7PlusEndpoint,
    names: readonly string[],
    steps: DoctorSteps,
    formatUrl: (e: S7PlusEndpoint) => string,
  ): Promise<void> {
    const doctor = new PlusDoctor(steps, formatUrl);
    try {
      await doctor.run(endpoint, names);
    } finally {
      await doctor.dispose();
    }
  },
});

/** protocol.py AccessLevel, in words (client/legitimation.ts Protection.level). */
const ACCESS_LEVELS: Readonly<Record<number, string>> = {
  0: 'no protection configured',
  1: 'full access',
  2: 'read access',
  3: 'HMI access',
  4: 'no access',
};

/** The handshake steps in their order; `password` only when one is given. */
type HandshakeName = 'cotp' | 'InitSSL' | 'TLS' | 'session' | 'password';

class PlusDoctor {
  private client: S7PlusClient | undefined;
  /** The handshake step that runs now: the one a connect failure belongs to. */
  private next: HandshakeName = 'cotp';

  /** `formatUrl`: an endpoint as the URL a user pastes (the pinned URL of a hint). */
  constructor(
    private readonly w: DoctorSteps,
    private readonly formatUrl: (e: S7PlusEndpoint) => string,
  ) {}

  async dispose(): Promise<void> {
    await this.client?.close();
  }

  async run(e: S7PlusEndpoint, names: readonly string[]): Promise<void> {
    await this.handshake(e);
    await this.identity();
    const table = await this.browse();
    for (const n of names) await this.check(n, table);
  }

  // ---------------------------------------------------------------- steps

  /** The URL `e` with `fingerprint=` pinning this certificate (and no insecure=true): what to try next. */
  private pinned(e: S7PlusEndpoint, fingerprint: string): string {
    const { insecure: _insecure, ca: _ca, ...rest } = e;
    return this.formatUrl({ ...rest, fingerprint });
  }

  /** TCP on a socket of its own, closed at once: a refusal or silence is told apart from the PLC's later answers. */
  private async tcp(e: S7PlusEndpoint, where: string): Promise<void> {
    try {
      const socket = await openTcp({
        host: e.host,
        port: e.port,
        timeout: Math.min(e.timeout, this.w.ms),
        signal: this.w.signal,
        keepAliveMs: 0,
      });
      socket.destroy();
    } catch (err) {
      this.w.failed('tcp', err, (p) => this.tcpFailure(e, where, p));
    }
    this.w.pass('tcp', `${where} accepts TCP connections`);
  }

  /** One connection by the client's own handshake; each step it tells becomes a passed step. */
  private async handshake(e: S7PlusEndpoint): Promise<void> {
    const where = `${e.host}:${e.port}`;
    await this.tcp(e, where);
    const password = this.w.options.password;
    const client = new S7PlusClient(
      { ...e, timeout: Math.max(1, Math.min(e.timeout, this.w.ms)) },
      {
        ...(password !== undefined ? { password } : {}),
        ...(this.w.options.symbols ? { symbols: this.w.options.symbols } : {}),
        handshake: (passed) => this.passed(e, where, passed),
      },
    );
    this.client = client;
    client.on('error', () => undefined);
    client.on('insecure', () => undefined); // the TLS step says it
    const onAbort = () => void client.close();
    this.w.signal.addEventListener('abort', onAbort, { once: true });
    try {
      await client.connect();
    } catch (err) {
      const step = this.next;
      this.w.failed(step, err, (p) => this.handshakeFailure(e, where, step, p));
    } finally {
      this.w.signal.removeEventListener('abort', onAbort);
    }
    if (password === undefined) this.w.pass('password', 'none given: the session has the access the CPU grants without a password');
  }

  private passed(e: S7PlusEndpoint, where: string, passed: HandshakeStep | { step: string; detail?: string }): void {
    switch (passed.step) {
      case 'cotp':
        this.w.pass(
          'cotp',
          `the CPU accepted the S7CommPlus connection request (called TSAP "SIMATIC-ROOT-${e.role.toUpperCase()}", calling TSAP 0x0600)`,
        );
        this.next = 'InitSSL';
        return;
      case 'InitSSL':
        this.w.pass('InitSSL', 'the CPU answered InitSSL: it speaks S7CommPlus');
        if (!e.tls) this.w.pass('TLS', 'tls=false: plain S7CommPlus V1, as the URL asks', PLUS_HINT.plainText);
        this.next = e.tls ? 'TLS' : 'session';
        return;
      case 'TLS': {
        const { certificate: c, protocol, trust } = passed as Extract<HandshakeStep, { step: 'TLS' }>;
        const how =
          trust === 'pinned'
            ? "matches the URL's fingerprint"
            : trust === 'ca'
              ? 'is signed by the CA of ca='
              : 'was accepted unchecked (insecure=true)';
        this.w.pass(
          'TLS',
          `${protocol}; the PLC's certificate ${how}: SHA-256 ${c.fingerprint}, subject ${c.subject}, valid ${c.validFrom} to ${c.validTo}`,
          trust === 'insecure' ? PLUS_HINT.insecure(this.pinned(e, c.fingerprint)) : undefined,
        );
        this.next = 'session';
        return;
      }
      case 'session': {
        const { sessionId, version } = passed as Extract<HandshakeStep, { step: 'session' }>;
        this.w.pass(
          'session',
          `S7CommPlus V${version}${version >= 2 ? ' with integrity ids' : ''}, session id 0x${sessionId.toString(16)}`,
        );
        this.next = 'password';
        return;
      }
      case 'password': {
        const { protection: p } = passed as Extract<HandshakeStep, { step: 'password' }>;
        const access = ACCESS_LEVELS[p.level] ?? `access level ${p.level}`;
        this.w.pass(
          'password',
          p.legitimated
            ? `the PLC took the password${p.form ? ` (${p.form} legitimation)` : ''}: the session has ${access}`
            : `the PLC wants no password: the session has ${access} without it`,
        );
        return;
      }
      default: {
        // A step this doctor does not know: shown as the client tells it.
        const detail = 'detail' in passed && typeof passed.detail === 'string' ? passed.detail : 'passed';
        this.w.pass(passed.step, detail);
      }
    }
  }

  private handshakeFailure(e: S7PlusEndpoint, where: string, step: HandshakeName, p: PlcError): never {
    let cause: unknown = p;
    while (cause instanceof Error && !(cause instanceof IsoConnectError)) cause = cause.cause;
    if (step === 'cotp') return this.cotpFailure(e, p, cause instanceof IsoConnectError ? cause : undefined);
    if (step === 'InitSSL') this.w.fail('InitSSL', p.message, /closed the connection/.test(p.message) ? PLUS_HINT.notPlusCpu : undefined);
    if (step === 'TLS') {
      if (p instanceof CertificateError) {
        const c = p.certificate;
        const detail =
          `the PLC's certificate was refused (${p.problem}): SHA-256 ${c.fingerprint}, subject ${c.subject}, issuer ${c.issuer}, ` +
          `valid ${c.notBefore.toISOString()} to ${c.notAfter.toISOString()}`;
        const url = this.pinned(e, c.fingerprint);
        if (p.problem === 'expired' || p.problem === 'not-yet-valid') this.w.fail('TLS', detail, PLUS_HINT.expired);
        if (p.problem === 'not-signed-by-ca') this.w.fail('TLS', detail, PLUS_HINT.notSignedByCa + url);
        this.w.fail('TLS', detail, PLUS_HINT.pin(url));
      }
      this.w.fail('TLS', p.message, PLUS_HINT.tlsRefused);
    }
    if (step === 'session') this.w.fail('session', p.message, e.tls ? PLUS_HINT.session : PLUS_HINT.plainAsked);
    this.w.fail(step, p.message, step === 'password' ? PLUS_HINT.password : undefined);
  }

  private tcpFailure(e: S7PlusEndpoint, where: string, p: PlcError): never {
    let c: unknown = p;
    let code: string | undefined;
    while (c instanceof Error && code === undefined) {
      code = (c as NodeJS.ErrnoException).code?.startsWith('E') ? (c as NodeJS.ErrnoException).code : undefined;
      c = c.cause;
    }
    if (p.code === 'TIMEOUT') this.w.fail('tcp', `no answer from ${where}: ${p.message}`, NETWORK_HINT.filtered(e.port));
    if (code === 'ECONNREFUSED')
      this.w.fail(
        'tcp',
        `${where} refused the connection (ECONNREFUSED): the host is up, but nothing listens on port ${e.port}`,
        NETWORK_HINT.refused,
      );
    if (code === 'ENOTFOUND' || code === 'EAI_AGAIN')
      this.w.fail('tcp', `"${e.host}" does not resolve (${code})`, NETWORK_HINT.unknownHost);
    if (code === 'EHOSTUNREACH' || code === 'ENETUNREACH') this.w.fail('tcp', `no route to ${where} (${code})`, NETWORK_HINT.noRoute);
    this.w.fail('tcp', p.message);
  }

  private cotpFailure(e: S7PlusEndpoint, p: PlcError, iso: IsoConnectError | undefined): never {
    const r = iso?.refusal;
    if (r?.kind === 'silent' || (!iso && p.code === 'TIMEOUT'))
      this.w.fail('cotp', `port ${e.port} accepts TCP but nothing answered the connection request: ${p.message}`, NETWORK_HINT.notIsoOnTcp);
    if (r?.kind === 'garbage') this.w.fail('cotp', `the answer is not ISO-on-TCP: ${r.message}`, NETWORK_HINT.otherProtocol);
    if (!iso) this.w.fail('cotp', p.message);
    const role = `SIMATIC-ROOT-${e.role.toUpperCase()}`;
    this.w.fail('cotp', `the CPU refused the S7CommPlus connection request (called TSAP "${role}"): ${p.message}`, PLUS_HINT.refusedTsap);
  }

  private async identity(): Promise<void> {
    const client = this.client!;
    try {
      const info = await client.info({ signal: this.w.signal });
      const who = info.orderCode
        ? `${info.orderCode}${info.firmware ? ` firmware ${info.firmware}` : ''}`
        : 'the CPU does not say what it is (no device string in its session)';
      this.w.pass('identity', `${who}; in ${info.state}`, info.state === 'STOP' ? PLUS_HINT.inStop : undefined);
    } catch (err) {
      this.w.failed('identity', err, (p) => this.w.fail('identity', p.message));
    }
  }

  private async browse(): Promise<SymbolTable | undefined> {
    const client = this.client!;
    try {
      const blocks = await client.dataBlocks({ signal: this.w.signal });
      const table = await client.browse({ signal: this.w.signal });
      const optimized = table.blocks.filter((b) => b.optimized === true).length;
      const typed = table.blocks.length;
      const detail =
        blocks.length === 0
          ? 'the PLC program has no data blocks'
          : `${blocks.length} data block${blocks.length === 1 ? '' : 's'} (${optimized} optimized, ${typed - optimized} standard` +
            `${typed < blocks.length ? `, ${blocks.length - typed} without type information` : ''}), ${table.entries.length} entries`;
      this.w.pass('browse', detail, blocks.length > 0 && typed === 0 ? PLUS_HINT.noTypes : undefined);
      return table;
    } catch (err) {
      return this.w.failed('browse', err, (p) => this.w.fail('browse', p.message));
    }
  }

  /** One step per given text: an address (standard DBs) or a name, read once, with its value and type. */
  private async check(text: string, table: SymbolTable | undefined): Promise<void> {
    let address = true;
    try {
      S7_TAG_SYNTAX.parse(text);
    } catch {
      address = false;
    }
    const step = `${address ? 'address' : 'symbol'} ${text}`;
    const client = this.client!;
    try {
      const r = (await client.readDetailed([text], { signal: this.w.signal }))[text]!;
      if (!r.ok) this.w.fail(step, r.error.message, address ? PLUS_HINT.address : PLUS_HINT.name);
      const type = address ? client.tag(text).type : (table?.lookup(text)?.type ?? '');
      this.w.pass(step, `${text} = ${textOf(realsShown(client, table, text, r.value))}${type ? ` (${type})` : ''}`);
    } catch (err) {
      this.w.failed(step, err, (p) => this.w.fail(step, p.message, address ? PLUS_HINT.address : PLUS_HINT.name));
    }
  }
}
