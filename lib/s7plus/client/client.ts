/**
 * S7PlusClient: S7CommPlus to an S7-1200/1500 on the shared link layer
 * (BaseClient: supervisor, tag cache, per-tag results, write safety). The
 * session (session.ts) owns the TLS socket over the COTP tunnel, numbers
 * every request and keeps one in flight; the handshake (handshake.ts) opens
 * it; close() ends the session with a DeleteObject before the link goes.
 *
 * The password (ConnectOptions.password) lives in a private field: it is in
 * no property, no JSON, no inspect() output, no error and no log line.
 */
import { BaseClient, endpointOptions, toResults, type ClientOptions } from '../../client/base';
import { ConnectionError, isLinkError, PlcError } from '../../errors';
import { COTP_DT_HEADER } from '../../iso/constants';
import type { Driver } from '../../link/driver';
import type { SymbolTable } from '../../symbols/model';
import type { Protocol, RequestOptions, Tag } from '../../types';
import { S7PLUS_DEFAULT_MAX_ITEMS, S7PLUS_URLS, type S7PlusEndpoint } from '../url';
import { openS7PlusSession } from './handshake';
import { BrowsedProgram, type ProgramChange } from './program';
import { browseTable } from './browse';
import { readPlcLimits, type SessionLimits } from './limits';
import { writeMixed } from './name-writes';
import { plusSyntax, readMixed } from './names';
import { cpuState, dataBlocks, type CpuState, type S7PlusDataBlock } from './services';
import type { S7PlusSession, S7PlusWireCounters } from './session';
import type { HandshakeStep, PeerCertificate } from './handshake';
import { parseDeviceString } from '../codec/identity';
import { readOnlyRefusals, type Protection } from './legitimation';
import { PushLink } from './push';
import { activeAlarms, languageIds, S7PlusAlarmSubscription } from './alarms';
import { ackRefusal } from '../../alarms/ack-guard';
import type { AlarmEvent, AlarmSubscribeOptions, PlcAlarm } from '../../alarms/model';
import type { S7PlusSubscription, SubscribeOptions, SubscriptionChange } from './subscription';

export type { PeerCertificate } from './handshake';
export type { CpuState, S7PlusDataBlock } from './services';
export type { Protection } from './legitimation';

/**
 * What `info()` tells of an S7-1200/1500 over S7CommPlus: the fields of the
 * S7 client's PlcInfo that S7CommPlus gives (order code, firmware, state),
 * and what only this connection has (the device string, the protocol
 * version, the PLC's certificate). No module name, serial number or plant
 * designation: no public source names an object that carries them.
 */
export interface S7PlusInfo {
  /** The order code (MLFB) of the device string: "6ES7 516-3AN02-0AB0". */
  orderCode: string | undefined;
  /** Major.minor, as the device string says it: "V3.1". */
  firmware: string | undefined;
  state: CpuState;
  /** ServerSessionVersion's device string as it came ("1;6ES7 516-3AN02-0AB0 ;V3.1"); undefined when the PLC sends none. */
  device: string | undefined;
  /** The S7CommPlus protocol version of the session: 1 (plain text) or 2 (TLS, integrity ids). */
  protocolVersion: number;
  /** The PLC's certificate over TLS. */
  certificate?: PeerCertificate;
}

/** A client's options: ClientOptions and the PLC's password. */
export interface S7PlusClientOptions extends Partial<ClientOptions> {
  /** For the PLC's protection levels that need one (legitimation). */
  password?: string;
  /** Told each handshake step as it passes, on every connect (the connection doctor shows them). */
  handshake?: (passed: HandshakeStep) => void;
}

/** The `insecure` event of a connection with `insecure=true`: which certificate it accepted unchecked. */
export interface InsecureEvent {
  certificate: PeerCertificate;
  message: string;
}

/**
 * S7PlusClient's events besides every client's (ClientEvents): `itemLimit` (the
 * PLC's item limit learnt), `programChanged` (the PLC's program changed under
 * a browsed table) and `insecure` (a certificate accepted unchecked).
 */
export interface S7PlusClientEvents {
  itemLimit: [event: { limit: number; was: number }];
  programChanged: [change: ProgramChange];
  insecure: [event: InsecureEvent];
}

/** A clean close waits this long at most for the PLC to answer the DeleteObject. */
const GOODBYE_MS = 2000;

export class S7PlusClient extends BaseClient<S7PlusSession, Tag, undefined, S7PlusClientEvents> {
  readonly protocol: Protocol = 's7plus';
  readonly endpoint: S7PlusEndpoint;
  /** Counters of the wire, cumulative over reconnects. */
  readonly stats: S7PlusWireCounters = { requestsSent: 0, bytesSent: 0, bytesReceived: 0, ignored: 0 };
  /** The PLC's certificate on the live TLS connection; undefined without one. */
  certificate: PeerCertificate | undefined;
  /** The device string of the live session (order code, firmware: codec/identity.ts); undefined when the PLC sends none. */
  device: string | undefined;
  /** The protection level of the live connection: what the password step found, or without a password the level the PLC grants (undefined when it tells none). */
  protection: Protection | undefined;
  readonly #password: string | undefined;
  private readonly onHandshakeStep: ((passed: HandshakeStep) => void) | undefined;
  /**
   * Items per read request: the URL's maxItems, else what the PLC's SystemLimits report (20 until it reports them),
   * lowered when the PLC refuses a request as too large.
   */
  private itemLimit: number;
  /** Items per write request, as itemLimit (SystemLimits LID 1001). */
  private writeLimit: number;
  /** Per session: its frame (the negotiated TPDU size), its read and write limits, and its SystemLimits read. */
  private readonly perSession = new WeakMap<S7PlusSession, SessionLimits>();

  /** The program of the live session (browse(), the program check); a new session browses again. */
  private program: { session: S7PlusSession; program: BrowsedProgram } | undefined;

  /** The table the subscriptions' session browsed: how their values look when no read by name browsed one. */
  private pushTable: SymbolTable | undefined;
  /** The session of the subscriptions (push.ts), opened at the first subscribe(). */
  private push: PushLink | undefined;
  /** The reconnect backoff of the client's options, for the subscriptions' session too. */
  private readonly pushBackoff: Pick<ClientOptions, 'backoff' | 'random'>;

  /** The alarm subscriptions (alarms.ts), each on a session of its own; the client's close() closes them. */
  private readonly alarmSubs = new Set<S7PlusAlarmSubscription>();
  /** Read-only and the allow-list as the client was given them: acknowledge() asks ackRefusal first. */
  private readonly ackGuard: { readOnly: boolean | undefined; allow: readonly string[] | undefined };

  protected readonly driver: Driver<S7PlusSession, Tag>;
  private readonly baseDriver = {
    openSession: (signal: AbortSignal) => this.openSession(signal),
    readValues: async (session: S7PlusSession, tags: readonly Tag[], signal?: AbortSignal) => {
      const limits = this.limitsOf(session);
      if (!limits.known) await this.plcLimits(session, limits, signal);
      return readMixed(session, tags, limits.read, this.programOf(session), signal);
    },
    readTags: async (session: S7PlusSession, tags: readonly Tag[], signal?: AbortSignal) => {
      const limits = this.limitsOf(session);
      if (!limits.known) await this.plcLimits(session, limits, signal);
      const { values, errors } = await readMixed(session, tags, limits.read, this.programOf(session), signal);
      return toResults(values, errors);
    },
    writeTags: async (session: S7PlusSession, items: readonly { tag: Tag; value: unknown }[], signal?: AbortSignal) => {
      const limits = this.limitsOf(session);
      if (!limits.known) await this.plcLimits(session, limits, signal);
      const results = await writeMixed(session, items, limits.write, this.programOf(session), signal);
      return this.#password === undefined ? readOnlyRefusals(session, this.name, items, results, signal) : results;
    },
    noBlockLength: 'S7CommPlus reads data blocks by their own layout: there is no PUT/GET layout to check',
    isLinkError,
  };

  constructor(endpoint: S7PlusEndpoint, options: S7PlusClientOptions = {}) {
    const { password, handshake, ...rest } = options;
    const effective = endpointOptions(S7PLUS_URLS.name(endpoint), endpoint, rest);
    super(effective);
    this.ackGuard = { readOnly: effective.readOnly, allow: effective.allow };
    this.driver = { syntax: plusSyntax(rest.symbols), ...this.baseDriver };
    this.endpoint = endpoint;
    this.#password = password;
    this.onHandshakeStep = handshake;
    this.pushBackoff = { ...(rest.backoff ? { backoff: rest.backoff } : {}), ...(rest.random ? { random: rest.random } : {}) };
    this.itemLimit = endpoint.maxItems ?? S7PLUS_DEFAULT_MAX_ITEMS;
    this.writeLimit = this.itemLimit;
  }

  /** The most items this client puts into one read request (the PLC's SystemLimits once read, or the URL's maxItems). */
  get maxItems(): number {
    return this.itemLimit;
  }

  /** The PLC refused a request of `items` items as a whole: requests carry half as many from now on (the `itemLimit` event). */
  private learnItemLimit(items: number): void {
    const limit = Math.max(1, Math.floor(items / 2));
    this.writeLimit = Math.min(this.writeLimit, Math.max(limit, 1));
    if (limit >= this.itemLimit) return;
    const was = this.itemLimit;
    this.itemLimit = limit;
    this.emit('itemLimit', { limit, was });
  }

  /** The limits of `session`'s requests (made at its first read or write). */
  private limitsOf(session: S7PlusSession): SessionLimits {
    const known = this.perSession.get(session);
    if (known) return known;
    const frame = (): number | undefined => this.perSession.get(session)?.frame;
    const refused = (items: number) => this.learnItemLimit(items);
    const limits: SessionLimits = {
      frame: undefined,
      // With maxItems in the URL the PLC's limits are not asked: the URL's is the override.
      known: this.endpoint.maxItems !== undefined,
      read: { maxItems: () => this.itemLimit, refused, maxFrame: frame },
      write: { maxItems: () => this.writeLimit, refused, maxFrame: frame },
    };
    this.perSession.set(session, limits);
    return limits;
  }

  /** Reads the PLC's SystemLimits, once per session (a failed read is tried again at the next request). */
  private async plcLimits(session: S7PlusSession, limits: SessionLimits, signal?: AbortSignal): Promise<void> {
    limits.asked ??= readPlcLimits(session, signal).then(
      (plc) => {
        if (plc.read !== undefined) this.itemLimit = plc.read;
        if (plc.write !== undefined) this.writeLimit = plc.write;
        limits.known = true;
      },
      (err: unknown) => {
        limits.asked = undefined;
        throw err;
      },
    );
    await limits.asked;
  }

  /** The CPU's operating state: RUN, STOP or UNKNOWN (theCPUexecUnit). */
  cpuState(options: RequestOptions = {}): Promise<CpuState> {
    return this.withSession((s) => cpuState(s, options.signal));
  }

  /** The CPU's identity (order code, firmware) from the session's device string, its state, and the connection's protocol and certificate. */
  info(options: RequestOptions = {}): Promise<S7PlusInfo> {
    return this.withSession(async (s) => {
      const state = await cpuState(s, options.signal);
      const device = this.device;
      const { orderCode, firmware } = device === undefined ? { orderCode: undefined, firmware: undefined } : parseDeviceString(device);
      const certificate = this.certificate;
      return { orderCode, firmware, state, device, protocolVersion: s.version, ...(certificate ? { certificate } : {}) };
    });
  }

  /** The data blocks of the PLC's program (standard and optimized), by number, with their names. */
  dataBlocks(options: RequestOptions = {}): Promise<S7PlusDataBlock[]> {
    return this.withSession((s) => dataBlocks(s, options.signal));
  }

  /**
   * The PLC's data blocks as a symbol table (lib/symbols/model.ts): names as
   * TIA writes them, IEC types, each entry's S7CommPlus access path, and the
   * byte and bit of standard blocks' members as the PLC gives them, and the
   * PLC tag table's I, Q and M names. Browsed once per connection (a
   * reconnect browses again) and again when a read or write by name finds
   * that the program changed (a download: the `programChanged` event).
   */
  browse(options: RequestOptions = {}): Promise<SymbolTable> {
    return this.withSession((s) => this.programOf(s).table(options.signal));
  }

  /**
   * The session's program: its table browsed once, checked after each read by name (and before each write) with one
   * request for the type objects' modification times; a download is the `programChanged` event and a new table.
   */
  /**
   * The PLC's table as the last session browsed it (after close() too: the values read were read through it), at once
   * (no request), or the one the subscriptions' session browsed; undefined before the first read, browse or subscription by name. What a value of a name looks like (how a REAL is shown: lib/symbols/reals.ts) is decided by it.
   */
  get browsedTable(): SymbolTable | undefined {
    return this.program?.program.latest ?? this.pushTable;
  }

  private programOf(session: S7PlusSession): BrowsedProgram {
    if (this.program?.session !== session) {
      const program = new BrowsedProgram(session, (change) => this.emit('programChanged', change));
      this.program = { session, program };
    }
    return this.program.program;
  }

  /** Runs `fn` on the live session; NOT_CONNECTED when there is none. */
  private async withSession<R>(fn: (session: S7PlusSession) => Promise<R>): Promise<R> {
    const session = this.session;
    if (!session?.alive) throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (the link is ${this.state})`);
    return fn(session);
  }

  /**
   * The PLC reports changes of `tags` (addresses or names) sampled every
   * `options.cycle` ms (default 100), on a session of their own on which
   * nothing is written. Resolves when the PLC created the subscription;
   * rejects with TagErrors naming each tag it cannot have (an unknown name:
   * INVALID_ADDRESS with the closest names), NOT_CONNECTED while the client
   * is not connected. `listener` is added for `change` before the first
   * notification. Created again after a reconnect; the client's close()
   * closes it.
   */
  subscribe(
    tags: readonly string[],
    options: SubscribeOptions = {},
    listener?: (change: SubscriptionChange) => void,
  ): Promise<S7PlusSubscription> {
    if (this.state !== 'connected') {
      return Promise.reject(new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (the link is ${this.state})`));
    }
    if (!this.push || this.push.done) {
      this.push = new PushLink({
        name: this.name,
        timeout: this.timeout,
        ...this.pushBackoff,
        open: (signal, hooks) => this.openSession(signal, hooks),
        browse: async (session) => (this.pushTable = await browseTable(session)),
        parse: (address) => this.tag(address),
      });
    }
    return this.push.subscribe(tags, options, listener);
  }

  /** The Program_Alarms active now (the alarm subsystem's list), texts in `languages` (`en-US`, …; default every one the PLC has). */
  alarms(options: RequestOptions & { languages?: readonly string[] } = {}): Promise<PlcAlarm[]> {
    return this.withSession((s) => activeAlarms(s, languageIds(options.languages), options.signal));
  }

  /**
   * The PLC's Program_Alarms as they come and go (issue #33), on a session of their own: resolves once the PLC
   * created the subscription (its `active` holds the alarms active then); after a reconnect it is created again and
   * what came or went meanwhile is reported `during: 'outage'`. The client's close() closes it.
   */
  async subscribeAlarms(options: AlarmSubscribeOptions = {}, listener?: (e: AlarmEvent) => void): Promise<S7PlusAlarmSubscription> {
    if (this.state !== 'connected') throw new ConnectionError('NOT_CONNECTED', `not connected to ${this.name} (the link is ${this.state})`);
    const sub = new S7PlusAlarmSubscription(
      { name: this.name, timeout: this.timeout, ...this.pushBackoff, open: (signal, hooks) => this.openSession(signal, hooks) },
      options,
    );
    if (listener) sub.on('event', listener);
    this.alarmSubs.add(sub);
    const close = sub.close.bind(sub);
    sub.close = () => {
      this.alarmSubs.delete(sub);
      return close();
    };
    await sub.start();
    return sub;
  }

  /**
   * Acknowledging a Program_Alarm over S7CommPlus: no public source shows the request (docs/alarms.md says what is
   * missing), so after the write safety (read-only, allow-list) it is refused with NOT_SUPPORTED; nothing is sent.
   */
  acknowledge(id: number, _options: RequestOptions = {}): Promise<void> {
    const refused = ackRefusal(id, this.ackGuard.readOnly, this.ackGuard.allow);
    if (refused) return Promise.reject(refused);
    return Promise.reject(
      new PlcError(
        'NOT_SUPPORTED',
        `acknowledge of alarm ${id} on ${this.name}: no public source shows how S7CommPlus acknowledges a Program_Alarm; acknowledge it on the HMI or with the program (docs/alarms.md)`,
        { tag: `ALARM${id}` },
      ),
    );
  }

  /** Ends the PLC's session (DeleteObject, at most 2 s), then closes as every client does. Always resolves. */
  override async close(): Promise<void> {
    await Promise.all([...this.alarmSubs].map((s) => s.close()));
    await this.push?.close();
    const session = this.session;
    if (session?.alive) await session.goodbye(Math.min(this.timeout, GOODBYE_MS));
    return super.close();
  }

  /** Opens a session: the client's own, or with `hooks` the subscriptions' one (push.ts), the same way (the password step included). */
  private async openSession(
    signal: AbortSignal,
    hooks?: { lost(session: S7PlusSession, err: PlcError): void; notify(data: Buffer): void },
  ): Promise<S7PlusSession> {
    // The TPDU size the PLC confirmed: a request frame stays within it (PLCSIM drops one past about 1 KB).
    let frame: number | undefined;
    const onStep = (passed: HandshakeStep) => {
      if (passed.step === 'cotp') frame = passed.maxPayload + COTP_DT_HEADER;
      this.onHandshakeStep?.(passed);
    };
    const opened = await openS7PlusSession(this.endpoint, {
      name: this.name,
      timeout: this.timeout,
      maxQueued: this.maxQueued,
      signal,
      stats: this.stats,
      lossError: (cause) => this.lossError(cause),
      lost: hooks?.lost ?? ((session, err) => this.sessionLost(session, err)),
      ...(hooks ? { notify: hooks.notify } : {}),
      insecure: (certificate) => this.warnInsecure(certificate),
      onStep,
      password: this.#password,
    });
    this.limitsOf(opened.session).frame = frame;
    this.certificate = opened.certificate;
    this.device = opened.device;
    this.protection = opened.protection;
    return opened.session;
  }

  private warnInsecure(certificate: PeerCertificate): void {
    const message =
      `${this.name}: insecure=true: the PLC's certificate is accepted unchecked (SHA-256 ${certificate.fingerprint}, ` +
      `subject ${certificate.subject}); pin it with fingerprint=${certificate.fingerprint}`;
    if (this.listenerCount('insecure') > 0) this.emit('insecure', { certificate, message } satisfies InsecureEvent);
    else process.emitWarning(message, 'PlcwireInsecureWarning');
  }
}
