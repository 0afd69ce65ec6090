/** The three simulators behind the Sim interface of support.ts, on ephemeral ports of 127.0.0.1. */
import type { Sim } from './support';

/* The library's simulators are loaded at run time so this file compiles while a driver is still being written. */
const lib = (p: string): any => require(`../../lib/${p}`);

export async function s7Sim(): Promise<Sim> {
  const { S7Server } = lib('s7/server');
  const { PlcMemory } = lib('sim/memory');
  const memory = new PlcMemory();
  let server = new S7Server({ port: 0, memory, profile: 's7-1500' });
  const port: number = await server.listen();
  const db = () => memory.area('DB', 1) as Buffer;
  return {
    protocol: 's7',
    url: `s7://127.0.0.1:${port}?rack=0&slot=1&timeout=1000`,
    addr: (i) => `DB1.DBW${2 * i}:INT`,
    set: (i, v) => void db().writeInt16BE(v, 2 * i),
    get: (i) => db().readInt16BE(2 * i),
    missing: 'DB999.DBW0:INT',
    connectionCount: () => server.connectionCount,
    stop: () => server.close(),
    restart: async () => {
      server = new S7Server({ port, memory, profile: 's7-1500' });
      await server.listen();
    },
    close: () => server.close(),
  };
}

export async function fetchWriteSim(): Promise<Sim> {
  const { FetchWriteServer } = lib('fetchwrite/server');
  const { PlcMemory } = lib('sim/memory');
  const memory = new PlcMemory();
  let server = new FetchWriteServer({ fetchPort: 0, writePort: 0, memory });
  const ports: { fetchPort: number; writePort: number } = await server.listen();
  const db = () => memory.area('DB', 1) as Buffer;
  return {
    protocol: 'fetchwrite',
    url: `fetchwrite://127.0.0.1?fetchPort=${ports.fetchPort}&writePort=${ports.writePort}&timeout=1000`,
    addr: (i) => `DB1,INT${2 * i}`,
    set: (i, v) => void db().writeInt16BE(v, 2 * i),
    get: (i) => db().readInt16BE(2 * i),
    missing: 'DB200,INT0', // DB 1..255 is reachable; the simulator has DB1..DB100
    connectionCount: () => server.connectionCount,
    stop: () => server.close(),
    restart: async () => {
      server = new FetchWriteServer({ fetchPort: ports.fetchPort, writePort: ports.writePort, memory });
      await server.listen();
    },
    close: () => server.close(),
  };
}

/** Freeport over a serial device server (freeport+tcp): stations 5, 6, 7 hold two INTs each. */
export async function freeportSim(): Promise<Sim> {
  const { FreeportBus } = lib('freeport/bus');
  const STATIONS = [5, 6, 7];
  const data: Record<number, Buffer> = {};
  let bus = new FreeportBus({ stations: STATIONS });
  const port: number = await bus.listenTcp({ port: 0 });
  const slot = (i: number) => ({ station: STATIONS[Math.floor(i / 2)]!, offset: 2 * (i % 2) });
  const buffer = (station: number) => bus.station(station).data as Buffer;
  return {
    protocol: 'freeport',
    url: `freeport+tcp://127.0.0.1:${port}?timeout=300&retries=0`,
    addr: (i) => `ST${slot(i).station},INT${slot(i).offset}`,
    set: (i, v) => void buffer(slot(i).station).writeInt16BE(v, slot(i).offset),
    get: (i) => buffer(slot(i).station).readInt16BE(slot(i).offset),
    missing: 'ST30,INT0',
    connectionCount: () => bus.connectionCount,
    stop: async () => {
      for (const s of STATIONS) data[s] = Buffer.from(buffer(s));
      await bus.close();
    },
    restart: async () => {
      bus = new FreeportBus({ stations: Object.fromEntries(STATIONS.map((s) => [s, data[s]!])) });
      await bus.listenTcp({ port });
    },
    close: () => bus.close(),
  };
}
