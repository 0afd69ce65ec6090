/**
 * S7PlusService: the S7CommPlus side of a simulated S7-1200/1500. The S7
 * simulator (lib/s7/server) hands it each connection whose COTP CR calls an
 * S7CommPlus TSAP, so both protocols share one port and one memory as on a
 * CPU: standard DBs are the S7 simulator's, read and written over either
 * protocol; optimized DBs are served here by name only.
 */
import { X509Certificate } from 'node:crypto';
import type { Socket } from 'node:net';
import type * as tls from 'node:tls';
import type { PlcMemory } from '../../sim/memory';
import type { CompileOptions, SymbolSource } from '../../symbols/model';
import { formatDeviceString, parseDeviceString } from '../codec/identity';
import { fingerprint256 } from '../transport/cert';
import { serverSecureContext } from '../transport/server-tls';
import { PlusConnection } from './connection';
import { dataBlockImages } from '../../sim/symbol-memory';
import { systemLimitsOf, uniformLimits, type SystemLimitValues } from './limits';
import { buildPlusModel, type PlusModel } from './model';
import { isS7PlusRequest } from './tsap';
import type { AlarmDefinition } from '../../alarms/model';
import { AlarmSubsystem } from './alarms';

export type { PlusModel } from './model';

/**
 * The request frame the CPU takes: the TPDU size its connection confirm negotiates (tsap.ts: code 0x0A, 1024 bytes).
 * PLCSIM Advanced V8 (CPU 1511) answered a read frame of about 860 bytes and dropped the connection on one of about
 * 1060 (s7commplus (MIT) client.py, the comment of max_request_bytes; server.py "past about 1 KB").
 */
const DEFAULT_MAX_REQUEST_BYTES = 1024;

export interface S7PlusOptions {
  /** The DB and UDT sources (and symbol tables) the CPU's program is built from, as `--source` gives them. */
  readonly sources: readonly SymbolSource[];
  /** Block numbers by name, as `--db` gives them. */
  readonly db?: CompileOptions['db'];
  /** The CPU's certificate and key (PEM). `false`: the CPU is configured without secure communication and speaks S7CommPlus in plain text. */
  readonly tls: { readonly cert: string | Buffer; readonly key: string | Buffer } | false;
  /**
   * Items one request may carry, read or write, reported as SystemLimits; more resets the connection. Default: the
   * profile's (limits.ts: an S7-1200 50, an S7-1500 100).
   */
  readonly maxItems?: number;
  /** The CPU's password: a session has read access until it legitimates with it (over TLS). Never logged. */
  readonly password?: string;
  /** Bytes one request frame may have (header to trailer, after TLS); more resets the connection. Default 1024, the negotiated TPDU size. */
  readonly maxRequestBytes?: number;
  /**
   * The device string of ServerSessionVersion (`1;<order number>;V<firmware>`), default an S7-1500 at V3.1:
   * its firmware decides the form of legitimation the CPU takes (V2.9 to V3.0: the legacy one).
   */
  readonly device?: string;
  /**
   * The Program_Alarms of the CPU's program (issue #33): each comes when its trigger tag goes TRUE and goes when it
   * goes FALSE, to every alarm subscription and in the active-alarm list (server/alarms.ts). `plcwire serve s7
   * --alarms F` gives the file's definitions.
   */
  readonly alarms?: readonly AlarmDefinition[];
}

/** What the S7 simulator gives each S7CommPlus connection. */
export interface PlusLink {
  onFrame(frame: Buffer): void;
  dispose(): void;
}

export class S7PlusService {
  private current: PlusModel;
  /** The running program's optimized DBs (PUT/GET refuses them): one set, refilled by reload(), that connections keep. */
  readonly optimizedDbs = new Set<number>();
  private readonly db: CompileOptions['db'] | undefined;
  /** SHA-256 of the certificate (DER), 64 upper-case hex digits; undefined in plain text. */
  readonly fingerprint: string | undefined;
  private readonly secureContext: tls.SecureContext | undefined;
  private readonly limits: SystemLimitValues | undefined;
  private readonly maxRequestBytes: number;
  private nextSession = 0x3a0;
  private readonly device: string | undefined;
  /** The CPU's alarm subsystem: the Program_Alarms of `S7PlusOptions.alarms` (none: a quiet one). */
  readonly alarms: AlarmSubsystem;
  /** The CPU's password (`S7PlusOptions.password`): a private field, so no inspect(), JSON or log shows it. */
  readonly #password: string | undefined;

  constructor(options: S7PlusOptions) {
    this.db = options.db;
    this.current = buildPlusModel(options.sources, options.db ? { db: options.db } : {});
    for (const n of this.current.optimizedDbs) this.optimizedDbs.add(n);
    this.limits = options.maxItems === undefined ? undefined : uniformLimits(options.maxItems);
    this.#password = options.password;
    this.device = options.device;
    this.maxRequestBytes = options.maxRequestBytes ?? DEFAULT_MAX_REQUEST_BYTES;
    this.alarms = new AlarmSubsystem(options.alarms ?? [], () => this.current);
    if (options.tls) {
      this.secureContext = serverSecureContext(options.tls);
      this.fingerprint = fingerprint256(new X509Certificate(options.tls.cert).raw);
    }
  }

  /** The program the CPU runs now (reload() replaces it). */
  get model(): PlusModel {
    return this.current;
  }

  /**
   * A download: the program of `sources` (with `db`, else the numbers given at construction) replaces the running
   * one, as TIA's download does on a CPU. Type objects whose layout is unchanged keep their modification time
   * (attribute 529), changed and new ones get a later one: what clients see as the program change. With `memory`
   * (the S7 simulator's), a data block whose layout is unchanged keeps its bytes, a new or changed one holds what its
   * sources give after a download, one no longer in the program is deleted; the I, Q and M areas are kept. Sources
   * that do not compile are a SourceError and the running program stays.
   */
  reload(sources: readonly SymbolSource[], memory?: PlcMemory, db: CompileOptions['db'] = this.db): PlusModel {
    const before = this.current;
    const after = buildPlusModel(sources, db ? { db } : {}, before);
    if (memory) {
      const images = dataBlockImages(after.table);
      const layoutOf = (m: PlusModel, number: number) => {
        const d = m.dbs.find((x) => x.number === number);
        return d && `${d.length} ${m.layouts.get(d.type.rid)}`;
      };
      for (const number of memory.dataBlockNumbers()) if (!images.has(number)) memory.deleteDataBlock(number);
      for (const [number, image] of images) {
        if (memory.area('DB', number) && layoutOf(before, number) === layoutOf(after, number)) continue;
        memory.createDataBlock(number, image.length);
        image.copy(memory.area('DB', number)!);
      }
    }
    this.current = after;
    this.optimizedDbs.clear();
    for (const n of after.optimizedDbs) this.optimizedDbs.add(n);
    return after;
  }

  /** True when the CPU has a password: sessions have read access until they give it. */
  get protected(): boolean {
    return this.#password !== undefined;
  }

  /** True when a COTP CR asks for S7CommPlus. */
  claims(frame: Buffer): boolean {
    return isS7PlusRequest(frame);
  }

  /** Opens a connection on the CR `frame` (S7Server calls it for each CR that `claims` accepts). */
  open(
    frame: Buffer,
    socket: Socket,
    cpu: {
      readonly memory: PlcMemory;
      readonly state: 'RUN' | 'STOP';
      /** The S7 simulator's CPU services: its profile's identity, the same order code and firmware PUT/GET's SZL gives. */
      readonly cpu?: { readonly identity: { readonly orderCode: string; readonly firmware: string } };
    },
    hostile: (err: Error) => void,
  ): PlusLink {
    const service = this;
    const identity = cpu.cpu?.identity;
    // The trigger tags live in the CPU's memory, the one every connection shares.
    this.alarms.attach(cpu.memory);
    const device = identity ? formatDeviceString(identity.orderCode, identity.firmware) : undefined;
    return new PlusConnection(
      {
        cpu: {
          // A reload replaces the program under running sessions, as a download does on a CPU.
          get model() {
            return service.current;
          },
          memory: cpu.memory,
          mode: () => cpu.state,
          alarms: this.alarms,
          // The limits of the CPU the session's device string names (a test's before the profile's).
          limits: this.limits ?? systemLimitsOf(this.device ? parseDeviceString(this.device).orderCode : identity?.orderCode),
        },
        secureContext: this.secureContext,
        session: {
          maxRequestBytes: this.maxRequestBytes,
          newSessionId: () => this.nextSession++,
          password: this.#password,
          // The device string given to the service (a test's firmware) before the profile's.
          device: this.device ?? device,
        },
        socket,
        close: (reason) => (reason ? hostile(reason) : socket.end()),
      },
      frame,
    );
  }
}
