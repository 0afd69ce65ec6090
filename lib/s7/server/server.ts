/**
 * S7Server: an in-process S7 PLC over real TCP (ISO-on-TCP). It negotiates
 * like a real CPU (offered PDU size, parallel jobs, connection limit), checks
 * rack/slot, serves Read/Write Var on PlcMemory, refuses oversized PDUs, and
 * can inject faults. Hostile frames close only the connection that sent them.
 */
import { EventEmitter } from 'node:events';
import * as net from 'node:net';
import { FrameReader } from '../../link/framer';
import { PlcMemory } from '../../sim/memory';
import { memoryFromSymbols } from '../../sim/symbol-memory';
import { ProtocolError } from '../../errors';
import { HeaderError, MIN_PDU_SIZE, Rosctr, S7Function } from '../constants';
import { DR_ADDRESS_UNKNOWN, DR_CONGESTION, MAX_FRAME, TPDU_SIZE_CODE, tpduBytes } from '../../iso/constants';
import { jobItemCount, s7Rosctr } from '../codec/pdu-decode';
import { isControlJob } from '../codec/control';
import type { DiagnosticEntry } from '../codec/diagnostics';
import { CyclicService, isCyclicRequest } from './cyclic';
import { CpuServices, newServiceSession, type ServiceSession, type SimulatorMode, type StopCause } from './services';
import { checkTpkt, decodeCotp, decodeS7, encodeConnectionConfirm, encodeDisconnectRequest, encodeSetupAck } from '../codec';
import { firstItems } from './items';
import { jobFunction, jobPduRef, refuseJob, serveRead, serveWrite, type JobContext } from './jobs';
import { IDENTITIES, PROFILES, toMemoryLayout, tsapRefusal, type CpuProfile } from './profiles';
import { refusal, type S7Faults, type S7PlusLink, type S7RefusedEvent, type S7RequestEvent, type S7ServerOptions } from './server-options';

export { IDENTITIES, PROFILES, type CpuIdentity, type CpuProfile, type S7Profile } from './profiles';
export { STOP_CAUSES, type SimulatorMode, type StopCause } from './services';
export { refusalLine, type S7Faults, type S7RefusedEvent, type S7RequestEvent, type S7ServerOptions } from './server-options';

/** The CPU's COTP source reference. */
const CPU_REF = 0x0001;
/** Jobs a client may queue beyond AmQ before it is treated as hostile. */
const MAX_QUEUED = 256;

interface Connection {
  socket: net.Socket;
  reader: FrameReader;
  stage: 'cotp' | 'setup' | 'jobs';
  /** The largest PDU this connection may negotiate (the TPDU size can lower it). */
  pduLimit: number;
  ctx: JobContext;
  services: ServiceSession;
  maxJobs: number;
  running: number;
  queue: Buffer[];
  timers: Set<NodeJS.Timeout>;
  counted: boolean;
  plus?: S7PlusLink | undefined;
}

/**
 * Events: `listening` (port), `connection` (count), `disconnect` (count), `mode` (RUN/STOP),
 * `refused` (S7RefusedEvent), `request` (S7RequestEvent), `error` (only when
 * listened to). The memory emits `read` and `write` (MemoryAccess).
 */
export class S7Server extends EventEmitter {
  readonly memory: PlcMemory;
  readonly profile: CpuProfile;
  readonly faults: S7Faults;
  /** Items served per job (S7ServerOptions.maxItems); may be changed at any time. */
  maxItems: number | undefined;
  /** The system side: mode, clock, diagnostic buffer, blocks, protection (also reached through the members below). */
  readonly cpu: CpuServices;
  private readonly host: string;
  private readonly wantPort: number;
  private server: net.Server | undefined;
  private readonly connections = new Set<Connection>();
  private boundPort = 0;
  private counted = 0;
  private readonly plus: S7ServerOptions['s7plus'];
  private cyclic: CyclicService | undefined;
  private readonly missingDb = (db: number): boolean => {
    const m = this.faults.missingDb;
    return typeof m === 'number' ? m === db : m !== undefined && m.includes(db);
  };

  constructor(options: S7ServerOptions = {}) {
    super();
    this.host = options.host ?? '127.0.0.1';
    this.wantPort = options.port ?? 102;
    const profile = options.profile ?? 's7-1500';
    const resolved = typeof profile === 'string' ? PROFILES[profile] : profile;
    // Only a name can miss: an object profile is its own resolution.
    // eslint-disable-next-line @typescript-eslint/no-base-to-string
    if (!resolved) throw new TypeError(`unknown S7 profile "${String(profile)}" (${Object.keys(PROFILES).join(', ')})`);
    this.profile = resolved;
    const layout = options.layout ? toMemoryLayout(options.layout) : resolved.layout;
    this.plus = options.s7plus;
    // The S7CommPlus program's data blocks, when it has any (a CPU holds those downloaded to it); else the layout's.
    const symbols = options.symbols ?? (options.s7plus?.model.table.blocks.length ? options.s7plus.model.table : undefined);
    this.memory = options.memory ?? (symbols ? memoryFromSymbols(symbols, layout) : new PlcMemory(layout));
    if (options.maxItems !== undefined && !(Number.isInteger(options.maxItems) && options.maxItems >= 1 && options.maxItems <= 255)) {
      throw new TypeError(`maxItems must be a whole number 1..255, got ${String(options.maxItems)}`);
    }
    this.maxItems = options.maxItems;
    const identity = { ...(typeof profile === 'string' ? IDENTITIES[profile] : IDENTITIES['s7-1500']), ...options.identity };
    this.cpu = new CpuServices(this.memory, Object.freeze(identity), {
      maxConnections: resolved.maxConnections,
      alarms: options.alarms,
      symbols,
    });
    this.cpu.on('mode', (mode: SimulatorMode) => this.emit('mode', mode));
    this.faults = {
      accessDenied: false,
      missingDb: undefined,
      latencyMs: 0,
      refuseConnections: false,
      silent: false,
      dropConnections: () => this.dropConnections(),
    };
  }

  /** RUN or STOP. A CPU in STOP still serves reads and writes of its memory (and every system service). */
  get state(): SimulatorMode {
    return this.cpu.mode;
  }

  /** Puts the CPU in STOP, logging the cause in the diagnostic buffer (default: a PLC stop command, 0x4304); false when it was in STOP. */
  stop(cause: StopCause | number = 'command'): boolean {
    return this.cpu.stop(cause);
  }

  /** Restarts the CPU (STOP → STARTUP → RUN, each step logged); false when it was in RUN. */
  start(kind: 'warm' | 'cold' = 'warm'): boolean {
    return this.cpu.start(kind);
  }

  /** Milliseconds the CPU clock runs ahead of the host clock (negative: behind). Settable; clients change it with setClock. */
  get clockOffset(): number {
    return this.cpu.clockOffset;
  }

  set clockOffset(ms: number) {
    this.cpu.clockOffset = ms;
  }

  /** The diagnostic buffer, newest entry first. */
  get diagnostics(): DiagnosticEntry[] {
    return this.cpu.diagnostics;
  }

  /** Protection level 1 (none), 2 (writes, stop/start, clock need the password), 3 (reads and upload too); a connection that gave the password works at level 1. */
  setProtection(level: 1 | 2 | 3, password?: string): void {
    this.cpu.setProtection(level, password);
  }

  /** The port listened on (after listen()). */
  get port(): number {
    return this.boundPort;
  }

  /** Connections that completed the COTP handshake and are open. */
  get connectionCount(): number {
    return this.counted;
  }

  listen(): Promise<number> {
    if (this.server) return Promise.resolve(this.boundPort);
    const server = net.createServer((socket) => this.accept(socket));
    this.server = server;
    return new Promise((resolve, reject) => {
      const onError = (err: Error) => {
        this.server = undefined;
        reject(err);
      };
      server.once('error', onError);
      server.listen(this.wantPort, this.host, () => {
        server.removeListener('error', onError);
        server.on('error', (err) => this.report(err));
        this.boundPort = (server.address() as net.AddressInfo).port;
        this.emit('listening', this.boundPort);
        resolve(this.boundPort);
      });
    });
  }

  /** Drops every client connection now. */
  dropConnections(): void {
    for (const c of this.connections) c.socket.destroy();
  }

  /** Stops listening and destroys every client socket. Always resolves. */
  close(): Promise<void> {
    const server = this.server;
    this.server = undefined;
    this.dropConnections();
    if (!server) return Promise.resolve();
    return new Promise((resolve) => server.close(() => resolve()));
  }

  private report(err: Error): void {
    if (this.listenerCount('error') > 0) this.emit('error', err);
  }

  private accept(socket: net.Socket): void {
    socket.setNoDelay(true);
    const conn: Connection = {
      socket,
      // The socket's chunks are ours: frames are cut from them without a copy.
      reader: new FrameReader(checkTpkt, MAX_FRAME, { copy: false }),
      stage: 'cotp',
      pduLimit: this.profile.pduSize,
      ctx: {
        memory: this.memory,
        pduSize: this.profile.pduSize,
        missingDb: undefined,
        s5CountersTimers: this.profile.s5CountersTimers !== false,
        optimizedDb: this.plus?.optimizedDbs,
      },
      services: newServiceSession(socket),
      maxJobs: 1,
      running: 0,
      queue: [],
      timers: new Set(),
      counted: false,
    };
    this.connections.add(conn);
    socket.on('data', (chunk: Buffer) => this.onData(conn, chunk));
    socket.on('error', () => undefined);
    socket.on('close', () => {
      this.connections.delete(conn);
      for (const t of conn.timers) clearTimeout(t);
      conn.timers.clear();
      conn.queue.length = 0;
      conn.plus?.dispose();
      if (conn.counted) {
        conn.counted = false;
        this.counted--;
        this.emit('disconnect', this.counted);
      }
    });
  }

  private onData(conn: Connection, chunk: Buffer): void {
    // An S7CommPlus link reads the socket itself (its COTP tunnel) once it confirmed the CR.
    if (conn.plus) return;
    const socket = conn.socket;
    let frames: Buffer[];
    try {
      frames = conn.reader.push(chunk);
    } catch (err) {
      return this.hostile(conn, err, chunk);
    }
    // Several answers to coalesced requests leave in one segment.
    socket.cork();
    let current: Buffer | undefined;
    try {
      for (current of frames) {
        if (socket.destroyed) break;
        this.onFrame(conn, current);
      }
    } catch (err) {
      this.hostile(conn, err, current);
    } finally {
      if (!socket.destroyed) socket.uncork();
    }
  }

  /** A frame that is not S7 (or breaks the protocol): a real CPU drops the connection; 'refused' says which and why. */
  private hostile(conn: Connection, err: unknown, frame?: Buffer): void {
    this.emit('refused', refusal('protocol-error', err instanceof Error ? err.message : String(err), conn.socket, frame));
    conn.socket.destroy();
  }

  private onFrame(conn: Connection, frame: Buffer): void {
    if (conn.plus) return conn.plus.onFrame(frame);
    if (conn.stage === 'jobs') {
      const func = jobFunction(frame);
      if (func !== 0) {
        if (this.listenerCount('request') > 0) {
          const kind = func === S7Function.ReadVar ? 'read' : 'write';
          this.emit('request', {
            kind,
            pduRef: jobPduRef(frame),
            items: jobItemCount(frame),
            bytes: frame.length,
          } satisfies S7RequestEvent);
        }
        return this.enqueue(conn, frame);
      }
      // Anything else must still be well-formed S7 (decodeS7 throws otherwise); it is refused in order with the jobs.
      const message = decodeS7(frame);
      if (message.kind === 'setup-request') throw new ProtocolError('setup communication sent twice');
      if (this.listenerCount('request') > 0 && (s7Rosctr(frame) === Rosctr.UserData || isControlJob(frame))) {
        const kind = s7Rosctr(frame) === Rosctr.UserData ? 'userdata' : 'control';
        this.emit('request', { kind, pduRef: message.pduRef, items: 0, bytes: frame.length } satisfies S7RequestEvent);
      }
      return this.enqueue(conn, frame);
    }
    if (conn.stage === 'cotp') return this.onConnectionRequest(conn, frame);
    const message = decodeS7(frame);
    if (message.kind !== 'setup-request') throw new ProtocolError(`expected setup communication, got ${message.kind}`);
    const { pduSize, maxAmqCalling } = message.params;
    // A request PDU size below MIN_PDU_SIZE is nonsense (one item and its answer do not fit): the offer is used.
    const pdu = pduSize < MIN_PDU_SIZE ? conn.pduLimit : Math.min(pduSize, conn.pduLimit);
    conn.maxJobs = Math.max(1, Math.min(maxAmqCalling, this.profile.maxJobs));
    conn.ctx.pduSize = pdu;
    conn.ctx.missingDb = this.missingDb;
    conn.stage = 'jobs';
    conn.socket.write(encodeSetupAck(message.pduRef, { maxAmqCalling: conn.maxJobs, maxAmqCalled: conn.maxJobs, pduSize: pdu }));
  }

  private onConnectionRequest(conn: Connection, frame: Buffer): void {
    const cr = decodeCotp(frame);
    if (cr.type !== 'CR') throw new ProtocolError(`expected a COTP connection request, got ${cr.type}`);
    const refuse = (reason: S7RefusedEvent['reason'], drReason: number, message: string) => {
      this.emit('refused', refusal(reason, message, conn.socket, reason === 'wrong-tsap' ? frame : undefined));
      conn.socket.end(encodeDisconnectRequest(cr.sourceRef, CPU_REF, drReason));
    };
    if (this.faults.refuseConnections) return refuse('refuse-fault', DR_CONGESTION, 'refuseConnections fault is on');
    if (this.counted >= this.profile.maxConnections) {
      return refuse('connection-limit', DR_CONGESTION, `all ${this.profile.maxConnections} connections of the CPU are in use`);
    }
    const plus = this.plus?.claims(frame) ? this.plus : undefined;
    const wrongTsap = plus ? undefined : tsapRefusal(this.profile, cr.callingTsap, cr.calledTsap);
    if (wrongTsap !== undefined) return refuse('wrong-tsap', DR_ADDRESS_UNKNOWN, wrongTsap);
    const tpdu = tpduBytes(cr.tpduSize) ? Math.min(cr.tpduSize, TPDU_SIZE_CODE) : TPDU_SIZE_CODE;
    // A PDU travels in one TPDU (3 bytes of COTP DT header): a CPU offers the largest of its sizes that fits.
    let limit = this.profile.pduSize;
    while (limit + 3 > tpduBytes(tpdu) && limit > 240) limit >>= 1;
    conn.pduLimit = limit;
    conn.stage = 'setup';
    conn.counted = true;
    this.counted++;
    // S7CommPlus (its CR called an S7CommPlus TSAP): the link confirms and serves every later frame.
    conn.plus = plus?.open(frame, conn.socket, this, (err) => this.hostile(conn, err));
    if (!conn.plus)
      conn.socket.write(
        encodeConnectionConfirm({
          sourceRef: CPU_REF,
          destinationRef: cr.sourceRef,
          callingTsap: cr.callingTsap,
          calledTsap: cr.calledTsap,
          tpduSize: tpdu,
        }),
      );
    this.emit('connection', this.counted);
  }

  private enqueue(conn: Connection, frame: Buffer): void {
    if (this.faults.latencyMs <= 0 && conn.running === 0 && conn.queue.length === 0) {
      // The hot path: answer at once.
      if (!this.faults.silent) conn.socket.write(this.answer(conn, frame));
      return;
    }
    if (conn.queue.length >= MAX_QUEUED) throw new ProtocolError(`client queued more than ${MAX_QUEUED} jobs beyond AmQ ${conn.maxJobs}`);
    conn.queue.push(frame);
    this.pump(conn);
  }

  /** Serves queued jobs, at most AmQ at once, each after the injected latency. */
  private pump(conn: Connection): void {
    while (conn.running < conn.maxJobs && conn.queue.length > 0) {
      const frame = conn.queue.shift()!;
      conn.running++;
      const serve = () => {
        conn.running--;
        if (conn.socket.destroyed) return;
        if (!this.faults.silent) {
          try {
            conn.socket.write(this.answer(conn, frame));
          } catch (err) {
            return this.hostile(conn, err, frame);
          }
        }
        this.pump(conn);
      };
      const latency = this.faults.latencyMs;
      if (latency > 0) {
        const timer = setTimeout(() => {
          conn.timers.delete(timer);
          serve();
        }, latency);
        conn.timers.add(timer);
      } else {
        serve();
      }
    }
  }

  private answer(conn: Connection, frame: Buffer): Buffer {
    const func = jobFunction(frame);
    const pduRef = jobPduRef(frame);
    if (func === 0) {
      // System services: userdata (SZL, clock, blocks, password) and the control jobs (stop, start, upload).
      if (isCyclicRequest(frame)) return (this.cyclic ??= new CyclicService(this.cpu.identity)).serve(frame, conn.socket, conn.ctx);
      if (s7Rosctr(frame) === Rosctr.UserData) return this.cpu.serveUserdata(frame, conn.services, conn.ctx.pduSize);
      if (isControlJob(frame)) return this.cpu.serveControl(frame, conn.services, conn.ctx.pduSize);
      // Any other job: "function not supported".
      return refuseJob(pduRef, HeaderError.FunctionNotSupported);
    }
    // S7-1200/1500 without PUT/GET: ack with header error 0x8104 (S7NetPlus/s7netplus#403 shows `32 02 … 81 04`).
    if (this.faults.accessDenied) return refuseJob(pduRef, HeaderError.FunctionNotSupported);
    // Protection level 2 refuses writes, 3 reads too, until the connection gave the password.
    if (this.cpu.refusesData(conn.services, func)) return refuseJob(pduRef, HeaderError.ProtectionLevel);
    const job = this.maxItems === undefined ? frame : firstItems(frame, this.maxItems);
    return func === S7Function.ReadVar ? serveRead(job, conn.ctx) : serveWrite(job, conn.ctx);
  }
}
