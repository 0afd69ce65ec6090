/**
 * The demo plant: all three simulators on fixed loopback ports, sharing one
 * simulated process. Used by `plcwire demo`, by `npm start` (which adds
 * Node-RED and a dashboard) and by tests (ports 0 = ephemeral).
 *
 * The S7-1200 holds the data blocks its program was downloaded with: DB1
 * compiled from the plant's source (PLANT_SOURCE, lib/plant/source.ts), 20
 * bytes holding its start values, and DB2 "Tank" with optimized access
 * (TANK_SOURCE), which PUT/GET refuses and S7CommPlus serves by name. As a
 * CPU with secure PG/HMI communication it speaks S7CommPlus over TLS on the
 * PUT/GET port, with a certificate made at start (or kept in `tlsDir`): its
 * fingerprint pins the s7plus:// URL (`urls.s7plus`). The CP (FETCH/WRITE) serves the same
 * memory, as a CP in the CPU's rack does.
 *
 * Beside it, on its own port, a classic S7-300 (`urls.s7classic`) runs the same
 * program on the same memory, so the tank's high level (lib/plant/alarms.ts)
 * comes as a classic ALARM_SQ there and as a Program_Alarm on the S7-1200.
 */
import { FetchWriteServer } from '../fetchwrite/server';
import { FreeportBus } from '../freeport/bus';
import { hostPart } from '../link/url-params';
import { S7Server } from '../s7/server';
import { S7PlusService } from '../s7plus/server';
import { generateCertificate } from '../s7plus/transport/cert';
import { certificateInDirectory } from '../s7plus/transport/cert-dir';
import type { PlcMemory } from '../sim/memory';
import { compileSymbols } from '../symbols';
import type { SymbolTable } from '../symbols/model';
import { CLASSIC_DEMO_ALARMS, PROGRAM_DEMO_ALARMS } from './alarms';
import { DemoProcess } from './process';
import { PLANT_DB_NUMBERS, PLANT_SOURCE, TANK_DB_NUMBERS, TANK_SOURCE } from './source';
import { TankBlock } from './tank';

export interface PlantPorts {
  s7: number;
  fetch: number;
  write: number;
  freeport: number;
  /** The classic S7-300 (ISO-on-TCP, the program's classic alarm blocks). */
  s7classic: number;
}

export const DEMO_PORTS: PlantPorts = Object.freeze({ s7: 10102, fetch: 12000, write: 12001, freeport: 14001, s7classic: 10103 });

/** Freeport stations of the demo: 5 holds the tank level (REAL), 6 the parts counter (DINT). */
export const DEMO_STATIONS = Object.freeze({ level: 5, parts: 6 });

export interface Plant {
  memory: PlcMemory;
  /** The plant's source compiled: what the demo flow's connections and `--symbols` read by name. */
  symbols: SymbolTable;
  process: DemoProcess;
  /** The optimized DB "Tank" (DB2) as the process keeps it. */
  tank: TankBlock;
  s7: S7Server;
  /** The classic S7-300 on the same memory: its alarm blocks raise the tank's high level as an ALARM_SQ. */
  s7classic: S7Server;
  /** The S7-1200's S7CommPlus side: its model (the blocks by name) and its certificate's SHA-256 `fingerprint`. */
  s7plus: S7PlusService;
  fetchwrite: FetchWriteServer;
  freeport: FreeportBus;
  ports: PlantPorts;
  /** `s7plus` carries the certificate's fingerprint: the pin a client needs to trust the simulator. */
  urls: { s7: string; s7plus: string; fetchwrite: string; freeport: string; s7classic: string };
  close(): Promise<void>;
}

export interface PlantOptions {
  host?: string;
  /** Fixed ports (DEMO_PORTS) for what is not given; `s7classic` not given beside other ports: an ephemeral one (0). */
  ports?: Partial<PlantPorts>;
  periodMs?: number;
  /**
   * A directory that keeps the S7-1200's certificate between runs (made on the first, lib/s7plus/transport/cert-dir.ts),
   * so the pinned `urls.s7plus` stays the same; `npm start` gives demoCertificateDir(). Default: one made at start.
   */
  tlsDir?: string;
}

/** The demo S7-1200's certificate. */
const DEMO_CERTIFICATE = Object.freeze({ commonName: 'plcwire demo S7-1200', keyType: 'ec' as const });

export async function startPlant(options: PlantOptions = {}): Promise<Plant> {
  const host = options.host ?? '127.0.0.1';
  // A caller that chose its ports before the S7-300 existed (tests: all 0) gets an ephemeral port for it, not a fixed one.
  const want = { ...DEMO_PORTS, ...(options.ports ? { s7classic: 0 } : {}), ...options.ports };
  const symbols = compileSymbols([PLANT_SOURCE], { db: PLANT_DB_NUMBERS });
  const certificate =
    options.tlsDir === undefined
      ? await generateCertificate(DEMO_CERTIFICATE)
      : await certificateInDirectory(options.tlsDir, DEMO_CERTIFICATE, 'tlsDir');
  const s7plus = new S7PlusService({
    sources: [PLANT_SOURCE, TANK_SOURCE],
    db: { ...PLANT_DB_NUMBERS, ...TANK_DB_NUMBERS },
    tls: { cert: certificate.cert, key: certificate.key },
    alarms: PROGRAM_DEMO_ALARMS,
  });
  // The memory is the S7CommPlus program's: DB1 as `symbols` places it, DB2 in the simulator's own layout.
  const s7 = new S7Server({ host, port: want.s7, profile: 's7-1200', s7plus });
  const memory = s7.memory;
  const s7classic = new S7Server({ host, port: want.s7classic, profile: 's7-300', memory, alarms: CLASSIC_DEMO_ALARMS });
  const tank = new TankBlock(memory, s7plus.model.table);
  // The process is the S7-1200's program: it stops with the CPU (the other links see the same memory held).
  const process = new DemoProcess(memory, options.periodMs ?? 100, s7.cpu, tank);
  const fetchwrite = new FetchWriteServer({ host, fetchPort: want.fetch, writePort: want.write, memory });
  const freeport = new FreeportBus({ stations: [DEMO_STATIONS.level, DEMO_STATIONS.parts] });
  const closeAll = async () => {
    process.stop();
    clearInterval(mirror);
    await Promise.allSettled([s7.close(), s7classic.close(), fetchwrite.close(), freeport.close()]);
  };
  // Freeport stations hold 4 bytes each: mirror the process into them every cycle.
  const mirror = setInterval(() => {
    const db = memory.area('DB', 1)!;
    db.copy(freeport.station(DEMO_STATIONS.level).data, 0, 0, 4);
    db.copy(freeport.station(DEMO_STATIONS.parts).data, 0, 8, 12);
  }, options.periodMs ?? 100);
  mirror.unref();
  try {
    const s7Port = await s7.listen();
    const classicPort = await s7classic.listen();
    const fw = await fetchwrite.listen();
    const fpPort = await freeport.listenTcp({ host, port: want.freeport });
    process.start();
    const ports = { s7: s7Port, fetch: fw.fetchPort, write: fw.writePort, freeport: fpPort, s7classic: classicPort };
    const h = hostPart(host);
    return {
      memory,
      symbols,
      process,
      tank,
      s7,
      s7classic,
      s7plus,
      fetchwrite,
      freeport,
      ports,
      urls: {
        s7: `s7://${h}:${ports.s7}?rack=0&slot=1`,
        s7plus: `s7plus://${h}:${ports.s7}?fingerprint=${s7plus.fingerprint!}`,
        fetchwrite: `fetchwrite://${h}?fetchPort=${ports.fetch}&writePort=${ports.write}`,
        freeport: `freeport+tcp://${h}:${ports.freeport}`,
        s7classic: `s7://${h}:${ports.s7classic}?rack=0&slot=2`,
      },
      close: closeAll,
    };
  } catch (err) {
    await closeAll();
    throw err;
  }
}
