/**
 * What a user sets and hears of the S7 simulator (server.ts): its options,
 * the faults it can inject, and the payloads of its 'request' and 'refused'
 * events.
 */
import type { Socket } from 'node:net';
import type { PlcMemory } from '../../sim/memory';
import type { SymbolTable } from '../../symbols/model';
import type { AlarmDefinition } from '../../alarms/model';
import type { CpuIdentity, CpuProfile, S7Layout, S7Profile } from './profiles';

export interface S7ServerOptions {
  /** Default 127.0.0.1: a simulator is not exposed to the network unless asked. */
  host?: string;
  /** Default 102; 0 picks a free port. */
  port?: number;
  /** Default 's7-1500'. */
  profile?: S7Profile | CpuProfile;
  memory?: PlcMemory;
  /** Memory layout when no `memory` is given (MemoryLayout or the JSON form `{ dbs, areas }`). */
  layout?: S7Layout;
  /**
   * Compiled DB sources (compileSymbols): the data blocks served are theirs,
   * at their declared lengths and holding their start values (lib/sim/symbol-memory.ts),
   * instead of the layout's; the other areas stay the layout's (or the profile's).
   */
  symbols?: SymbolTable;
  /**
   * Serve at most this many items per job, as snap7's server (20) and the
   * devices built on it: a longer job is served for its first N items and
   * answered as if those were all (items.ts). Default: no limit but
   * the PDU's, as Siemens CPUs.
   */
  maxItems?: number;
  /** What the CPU says about itself (order code, firmware, names …); the profile's defaults (S7-1500's for a custom CpuProfile) for what is not given. */
  identity?: Partial<CpuIdentity>;
  /**
   * S7CommPlus on the same port (lib/s7plus/server S7PlusService): a COTP CR
   * calling an S7CommPlus TSAP goes to it, as on an S7-1200/1500; its
   * program's blocks are the memory's, and PUT/GET refuses its optimized DBs.
   */
  s7plus?: S7PlusEndpoint;
  /**
   * The program's alarm blocks (AlarmDefinition, lib/alarms/model.ts; the `--alarms` file of `plcwire serve s7`):
   * an S7-300/400 raises each as its trigger tag goes TRUE / FALSE and serves the message service, the alarm query
   * and acknowledgement (lib/s7/server/alarms.ts). A CPU of another profile refuses those services (0x8104).
   */
  alarms?: readonly AlarmDefinition[];
}

/** The S7CommPlus side the simulator hands connections to (lib/s7plus/server S7PlusService). */
interface S7PlusEndpoint {
  readonly model: { readonly table: SymbolTable };
  /** The program's optimized DBs, which PUT/GET refuses; asked at each job (a reload of the program may change them). */
  readonly optimizedDbs: ReadonlySet<number>;
  /** True when a COTP CR calls an S7CommPlus TSAP. */
  claims(frame: Buffer): boolean;
  /**
   * Confirms the CR `frame` on `socket` and serves the connection from `cpu`, reading the socket itself from then on
   * (the simulator hands it over and reads no more of it); `hostile` reports a frame that breaks the protocol (the
   * simulator then drops the connection).
   */
  open(
    frame: Buffer,
    socket: Socket,
    cpu: {
      readonly memory: PlcMemory;
      readonly state: 'RUN' | 'STOP';
      /** The CPU's services: what it says about itself (the order code and firmware of its SZL). */
      readonly cpu: { readonly identity: { readonly orderCode: string; readonly firmware: string } };
    },
    hostile: (err: Error) => void,
  ): S7PlusLink;
}

/** One S7CommPlus connection: the simulator gives it the frames it cut after the CR in the CR's own chunk (none from a client that waits for the confirm), and tells it when the socket closed. */
export interface S7PlusLink {
  onFrame(frame: Buffer): void;
  dispose(): void;
}

/** Fault injection; every field can be changed at any time. */
export interface S7Faults {
  /** Answer every Read/Write Var with header error 0x8104, as an S7-1200/1500 without PUT/GET access. */
  accessDenied: boolean;
  /** Data blocks that answer "object does not exist" (0x0A) although they are in memory. */
  missingDb: number | readonly number[] | undefined;
  /** Delay each job by this many ms; at most the negotiated AmQ jobs of a connection are served at once (a CPU's latency model). */
  latencyMs: number;
  /** Refuse new connections (COTP disconnect request instead of a confirm). */
  refuseConnections: boolean;
  /** Stop answering jobs (connections stay open): a hung CPU. */
  silent: boolean;
  /** Drop every client connection now (a CPU restart or a pulled cable, as the clients see it). */
  dropConnections(): void;
}

export interface S7RequestEvent {
  /** Read/Write Var, or a system service: userdata (SZL, clock, blocks, password) or a control job (stop, start, upload). */
  kind: 'read' | 'write' | 'userdata' | 'control';
  pduRef: number;
  /** Number of items in the job (0 for system services). */
  items: number;
  /** Bytes of the request frame on the wire. */
  bytes: number;
}

/**
 * Why a connection was refused or dropped ('refused' event): the simulator
 * never closes a connection without one, so a log (plcwire serve prints them)
 * says which frame and why.
 */
export interface S7RefusedEvent {
  reason: 'connection-limit' | 'refuse-fault' | 'wrong-tsap' | 'protocol-error';
  message: string;
  /** The client, "address:port". */
  peer: string;
  /** The refused frame as hex (its first 64 bytes, "…" after them); absent when no frame is to blame. */
  frame?: string;
}

/** The event of a refusal of `socket`'s connection, for `frame` when one is to blame. */
export function refusal(reason: S7RefusedEvent['reason'], message: string, socket: Socket, frame?: Buffer): S7RefusedEvent {
  const peer = `${socket.remoteAddress ?? '?'}:${socket.remotePort ?? '?'}`;
  if (!frame) return { reason, message, peer };
  return { reason, message, peer, frame: frame.subarray(0, 64).toString('hex') + (frame.length > 64 ? '…' : '') };
}

/** One line for a log: `refused 127.0.0.1:50123 (protocol-error): … — frame 0300…`. */
export function refusalLine(e: S7RefusedEvent): string {
  return `refused ${e.peer} (${e.reason}): ${e.message}${e.frame ? ` — frame ${e.frame}` : ''}`;
}
