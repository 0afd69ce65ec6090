/**
 * S7Server: an in-process S7 PLC over real TCP (ISO-on-TCP). It negotiates
 * like a real CPU (offered PDU size, parallel jobs, connection limit), serves
 * Read/Write Var on PlcMemory, checks rack/slot, refuses oversized PDUs, and
 * can inject faults. Hostile frames close only the connection that sent them.
 */
import { EventEmitter } from 'node:events';
import * as net from 'node:net';
import { FrameReader } from '../link/framer';
import { PlcMemory, type MemoryLayout } from '../sim/memory';
import type { AreaName } from '../types';
import {
  DataTransportSize,
  FRAME_OVERHEAD,
  ReturnCode,
  S7Area,
  TransportSize,
  tpduBytes,
} from './constants';
import {
  checkTpkt,
  decodeCotp,
  decodeS7,
  encodeConnectionConfirm,
  encodeDisconnectRequest,
  encodeErrorAck,
  encodeReadResponse,
  encodeSetupAck,
  encodeWriteResponse,
  type ReadResponseItem,
  type S7Item,
  type S7WriteItem,
} from './codec';

export type S7Profile = 's7-300' | 's7-400' | 's7-1200' | 's7-1500';

export interface CpuProfile {
  /** PDU size the CPU offers (it answers min(requested, offered)). */
  pduSize: number;
  /** Parallel jobs (AmQ) the CPU offers. */
  maxJobs: number;
  /** Connections the CPU accepts at once; the next one is refused. */
  maxConnections: number;
  /** Slots the CPU answers on (rack 0). */
  slots: number[];
}

/**
 * Figures of real CPUs as they negotiate: S7-1200 offers PDU 240 and 3
 * parallel jobs and takes 8 PG/OP/S7 connections; S7-1500 offers PDU 960;
 * S7-300/400 CPUs sit in slot 2 (S7-400: often 3) and offer 240 / 480.
 */
export const PROFILES: Readonly<Record<S7Profile, CpuProfile>> = Object.freeze({
  's7-300': { pduSize: 240, maxJobs: 1, maxConnections: 16, slots: [2] },
  's7-400': { pduSize: 480, maxJobs: 8, maxConnections: 32, slots: [2, 3, 4] },
  's7-1200': { pduSize: 240, maxJobs: 3, maxConnections: 8, slots: [0, 1] },
  's7-1500': { pduSize: 960, maxJobs: 8, maxConnections: 32, slots: [0, 1] },
});

export interface S7ServerOptions {
  /** Default 127.0.0.1: a simulator is not exposed to the network unless asked. */
  host?: string;
  /** Default 102; 0 picks a free port. */
  port?: number;
  profile?: S7Profile | CpuProfile;
  memory?: PlcMemory;
  /** Memory layout when no `memory` is given. */
  layout?: MemoryLayout;
}

export interface S7Faults {
  /** Answer every job with header error 0x8104, as an S7-1200/1500 without PUT/GET access. */
  accessDenied: boolean;
  /** Delay each job by this many ms; at most `maxJobs` jobs of a connection are served at once. */
  latencyMs: number;
  /** Refuse new connections (COTP disconnect). */
  refuseConnections: boolean;
  /** Stop answering jobs (the connection stays open): a hung CPU. */
  silent: boolean;
}

export interface S7RequestEvent {
  kind: 'read' | 'write';
  pduRef: number;
  items: number;
  /** Bytes of the request frame on the wire. */
  bytes: number;
}

const SIZES: Readonly<Record<number, number>> = {
  [TransportSize.BIT]: 1,
  [TransportSize.BYTE]: 1,
  [TransportSize.CHAR]: 1,
  [TransportSize.WORD]: 2,
  [TransportSize.INT]: 2,
  [TransportSize.DWORD]: 4,
  [TransportSize.DINT]: 4,
  [TransportSize.REAL]: 4,
  [TransportSize.COUNTER]: 2,
  [TransportSize.TIMER]: 2,
};

const AREA_BY_CODE: Readonly<Record<number, AreaName>> = {
  [S7Area.I]: 'I',
  [S7Area.Q]: 'Q',
  [S7Area.M]: 'M',
  [S7Area.DB]: 'DB',
  [S7Area.C]: 'C',
  [S7Area.T]: 'T',
  [S7Area.PE_PA]: 'PE',
};

type S7Job = ReturnType<typeof decodeS7>;

interface Connection {
  socket: net.Socket;
  reader: FrameReader;
  stage: 'cotp' | 'setup' | 'jobs';
  pduSize: number;
  maxJobs: number;
  running: number;
  queue: { frame: Buffer; message: S7Job }[];
  counted: boolean;
}

/**
 * Events: `listening` (port), `connection` (count), `disconnect` (count),
 * `request` (S7RequestEvent), `error` (only if listened to). The memory
 * emits `read` and `write`.
 */
export class S7Server extends EventEmitter {
  readonly memory: PlcMemory;
  readonly profile: CpuProfile;
  readonly faults: S7Faults = { accessDenied: false, latencyMs: 0, refuseConnections: false, silent: false };
  private readonly host: string;
  private readonly wantPort: number;
  private server: net.Server | undefined;
  private readonly connections = new Set<Connection>();
  private boundPort = 0;

  constructor(options: S7ServerOptions = {}) {
    super();
    this.host = options.host ?? '127.0.0.1';
    this.wantPort = options.port ?? 102;
    const profile = options.profile ?? 's7-1500';
    this.profile = typeof profile === 'string' ? PROFILES[profile] : profile;
    if (!this.profile) throw new TypeError(`unknown S7 profile "${String(profile)}" (s7-300, s7-400, s7-1200, s7-1500)`);
    this.memory = options.memory ?? new PlcMemory(options.layout);
  }

  /** The port listened on (after listen()). */
  get port(): number {
    return this.boundPort;
  }

  /** Connections that completed the COTP handshake and are open. */
  get connectionCount(): number {
    let n = 0;
    for (const c of this.connections) if (c.counted) n++;
    return n;
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

  /** Drops every client connection now (a CPU restart or a cable pull as the clients see it). */
  dropConnections(): void {
    for (const c of this.connections) c.socket.destroy();
  }

  /** Stops listening and drops every client. Always resolves. */
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
      reader: new FrameReader(checkTpkt, 70_000),
      stage: 'cotp',
      pduSize: this.profile.pduSize,
      maxJobs: this.profile.maxJobs,
      running: 0,
      queue: [],
      counted: false,
    };
    this.connections.add(conn);
    socket.on('data', (chunk: Buffer) => {
      let frames: Buffer[];
      try {
        frames = conn.reader.push(chunk);
      } catch {
        socket.destroy();
        return;
      }
      for (const frame of frames) {
        if (socket.destroyed) return;
        this.onFrame(conn, frame);
      }
    });
    socket.on('error', () => undefined);
    socket.on('close', () => {
      this.connections.delete(conn);
      if (conn.counted) this.emit('disconnect', this.connectionCount);
    });
  }

  private onFrame(conn: Connection, frame: Buffer): void {
    try {
      if (conn.stage === 'cotp') return this.onConnectionRequest(conn, frame);
      const message = decodeS7(frame);
      if (conn.stage === 'setup') {
        if (message.kind !== 'setup-request') throw new Error('expected setup communication');
        conn.pduSize = Math.max(240, Math.min(message.params.pduSize, this.profile.pduSize));
        conn.maxJobs = Math.max(1, Math.min(message.params.maxAmqCalling || 1, this.profile.maxJobs));
        conn.stage = 'jobs';
        conn.socket.write(encodeSetupAck(message.pduRef, { maxAmqCalling: conn.maxJobs, maxAmqCalled: conn.maxJobs, pduSize: conn.pduSize }));
        return;
      }
      if (message.kind === 'read-request' || message.kind === 'write-request') {
        this.emit('request', { kind: message.kind === 'read-request' ? 'read' : 'write', pduRef: message.pduRef, items: message.items.length, bytes: frame.length } satisfies S7RequestEvent);
      }
      conn.queue.push({ frame, message });
      this.pump(conn);
    } catch {
      // A frame that is not S7: a real CPU drops the connection.
      conn.socket.destroy();
    }
  }

  private onConnectionRequest(conn: Connection, frame: Buffer): void {
    const cr = decodeCotp(frame);
    if (cr.type !== 'CR') throw new Error('expected a COTP connection request');
    const refuse = () => {
      conn.socket.end(encodeDisconnectRequest(cr.sourceRef, 0x0001, 0x80));
    };
    if (this.faults.refuseConnections || this.connectionCount >= this.profile.maxConnections) return refuse();
    // TSAPs of the rack/slot form (type 1..3 in the high byte) must name this CPU.
    const type = cr.calledTsap >> 8;
    if (type >= 1 && type <= 3) {
      const rack = (cr.calledTsap >> 5) & 0x07;
      const slot = cr.calledTsap & 0x1f;
      if (rack !== 0 || !this.profile.slots.includes(slot)) return refuse();
    }
    const tpdu = tpduBytes(cr.tpduSize) ? Math.min(cr.tpduSize, 0x0a) : 0x0a;
    conn.stage = 'setup';
    conn.counted = true;
    conn.socket.write(
      encodeConnectionConfirm({ sourceRef: 0x0001, destinationRef: cr.sourceRef, callingTsap: cr.callingTsap, calledTsap: cr.calledTsap, tpduSize: tpdu }),
    );
    this.emit('connection', this.connectionCount);
  }

  /** Serves queued jobs, at most maxJobs at once, each after the injected latency. */
  private pump(conn: Connection): void {
    while (conn.running < conn.maxJobs && conn.queue.length > 0) {
      const { frame, message } = conn.queue.shift()!;
      conn.running++;
      const serve = () => {
        conn.running--;
        if (!conn.socket.destroyed && !this.faults.silent) {
          try {
            const reply = this.serve(conn, frame, message);
            if (reply) conn.socket.write(reply);
          } catch {
            conn.socket.destroy();
            return;
          }
        }
        this.pump(conn);
      };
      if (this.faults.latencyMs > 0) setTimeout(serve, this.faults.latencyMs);
      else serve();
    }
  }

  private serve(conn: Connection, frame: Buffer, message: S7Job): Buffer | undefined {
    if (message.kind !== 'read-request' && message.kind !== 'write-request') {
      // Unknown or unsupported job: a CPU answers "function not supported".
      return encodeErrorAck(message.pduRef, 0x81, 0x04);
    }
    if (this.faults.accessDenied) return encodeErrorAck(message.pduRef, 0x81, 0x04);
    if (frame.length - FRAME_OVERHEAD > conn.pduSize) return encodeErrorAck(message.pduRef, 0x85, 0x00);
    if (message.kind === 'read-request') {
      const items = message.items.map((item) => this.readItem(item));
      // The answer must fit the negotiated PDU too: 14 bytes of header + items.
      let size = 14;
      items.forEach((it, i) => (size += 4 + it.data.length + (it.data.length % 2 === 1 && i < items.length - 1 ? 1 : 0)));
      if (size > conn.pduSize) return encodeErrorAck(message.pduRef, 0x85, 0x00);
      return encodeReadResponse(message.pduRef, items);
    }
    return encodeWriteResponse(message.pduRef, message.items.map((item) => this.writeItem(item)));
  }

  /** Where an item lives in memory: area, byte offset and byte length (C/T: 2 bytes per number). */
  private locate(item: S7Item): { area: AreaName; offset: number; length: number } | number {
    const area = AREA_BY_CODE[item.area];
    const size = SIZES[item.transportSize];
    if (!area || !size) return ReturnCode.DataTypeNotSupported;
    if (area === 'C' || area === 'T') {
      if (item.transportSize !== (area === 'C' ? TransportSize.COUNTER : TransportSize.TIMER) && item.transportSize !== TransportSize.BYTE && item.transportSize !== TransportSize.WORD) {
        return ReturnCode.DataTypeNotSupported;
      }
      return { area, offset: item.address * 2, length: item.transportSize === TransportSize.BYTE ? item.count : item.count * 2 };
    }
    if (item.transportSize === TransportSize.BIT) {
      if (item.count !== 1) return ReturnCode.DataTypeInconsistent;
      return { area, offset: item.address >> 3, length: 1 };
    }
    return { area, offset: item.address >> 3, length: item.count * size };
  }

  private readItem(item: S7Item): ReadResponseItem {
    const where = this.locate(item);
    if (typeof where === 'number') return { returnCode: where, transportSize: 0, data: Buffer.alloc(0) };
    const fault = this.memory.check(where.area, item.dbNumber, where.offset, where.length);
    if (fault) {
      return { returnCode: fault === 'NO_SUCH_AREA' ? ReturnCode.ObjectDoesNotExist : ReturnCode.AddressOutOfRange, transportSize: 0, data: Buffer.alloc(0) };
    }
    const buf = this.memory.area(where.area, item.dbNumber)!;
    if (this.memory.listenerCount('read') > 0) this.memory.emit('read', { area: where.area, dbNumber: item.dbNumber, offset: where.offset, length: where.length });
    if (item.transportSize === TransportSize.BIT) {
      const bit = (buf[where.offset]! >> (item.address & 7)) & 1;
      return { returnCode: ReturnCode.Success, transportSize: DataTransportSize.BIT, data: Buffer.of(bit) };
    }
    const octets = item.area === S7Area.C || item.area === S7Area.T;
    // A subarray of live memory: encodeReadResponse copies it into the frame at once.
    return { returnCode: ReturnCode.Success, transportSize: octets ? DataTransportSize.OCTET_STRING : DataTransportSize.BYTE, data: buf.subarray(where.offset, where.offset + where.length) };
  }

  private writeItem(item: S7WriteItem): number {
    const target = this.locate(item);
    if (typeof target === 'number') return target;
    const area: AreaName = target.area === 'PE' ? 'PA' : target.area;
    const fault = this.memory.check(area, item.dbNumber, target.offset, target.length);
    if (fault) return fault === 'NO_SUCH_AREA' ? ReturnCode.ObjectDoesNotExist : ReturnCode.AddressOutOfRange;
    if (item.transportSize === TransportSize.BIT) {
      if (item.data.length !== 1) return ReturnCode.DataTypeInconsistent;
      this.memory.writeBit(area, item.dbNumber, target.offset, item.address & 7, (item.data[0]! & 1) === 1);
      return ReturnCode.Success;
    }
    if (item.data.length !== target.length) return ReturnCode.DataTypeInconsistent;
    this.memory.write(area, item.dbNumber, target.offset, item.data);
    return ReturnCode.Success;
  }
}
