/** `plcwire serve <protocol>`: run a simulator until Ctrl-C. */
import { FetchWriteServer } from '../fetchwrite/server';
import { FreeportBus } from '../freeport/bus';
import { S7Server, type S7Profile } from '../s7/server';
import type { MemoryLayout } from '../sim/memory';
import type { SymbolTable } from '../symbols/model';
import { FREEPORT_BAUD_RATES } from '../url';
import { UsageError, intFlag, listFlag, stringFlag, type ParsedArgs } from './args';
import { readInputFile } from './files';
import { EXIT, untilInterrupted, type CliIo } from './io';
import { symbolsFlag } from './symbols';

export const SERVE_FLAGS = [
  'port',
  'host',
  'profile',
  'layout',
  'fetch-port',
  'write-port',
  'path',
  'baud',
  'tcp',
  'stations',
  'max-items',
];

const PROFILES: readonly S7Profile[] = ['s7-300', 's7-400', 's7-1200', 's7-1500', 's7-200', 'logo'];

/** The URL query that reaches each profile's CPU: rack/slot, or the TSAP pair a TSAP-addressed CPU accepts. */
const REACH: Readonly<Record<S7Profile, { query: string; addresses: string }>> = Object.freeze({
  's7-300': { query: 'rack=0&slot=2', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-400': { query: 'rack=0&slot=2', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-1200': { query: 'rack=0&slot=1', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-1500': { query: 'rack=0&slot=1', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-200': { query: 'localTsap=1000&remoteTsap=1001', addresses: 'VW0 VB10 M0.1' },
  logo: { query: 'localTsap=0100&remoteTsap=0200', addresses: 'VW0 V1024.0' },
});

export async function serve(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const [protocol, ...extra] = rest;
  if (extra.length > 0) throw new UsageError(`unexpected argument "${extra[0]}"`);
  const host = stringFlag(args, 'host') ?? '127.0.0.1';
  const say = (line: string) => io.stdout.write(`${line}\n`);
  let close: () => Promise<void>;
  switch (protocol) {
    case 's7': {
      const profile = (stringFlag(args, 'profile') ?? 's7-1500').toLowerCase() as S7Profile;
      if (!PROFILES.includes(profile)) throw new UsageError(`--profile must be one of ${PROFILES.join(', ')}`);
      // Without --layout the profile's own memory (DB1 only for s7-200 and logo).
      const layout = loadLayout(stringFlag(args, 'layout'));
      // --source: the data blocks of DB sources, at their declared lengths with their start values.
      const symbols = symbolsFlag(args, 'source');
      // --max-items: serve at most N items per job, as snap7's server (20) and the devices built on it.
      const maxItems = args.flags.has('max-items') ? intFlag(args, 'max-items', 20, 1, 255) : undefined;
      const server = new S7Server({
        host,
        port: intFlag(args, 'port', 102, 0, 65535),
        profile,
        ...(layout ? { layout } : {}),
        ...(symbols ? { symbols } : {}),
        ...(maxItems !== undefined ? { maxItems } : {}),
      });
      const port = await listen(() => server.listen(), 'port');
      say(`S7 simulator (${profile}) listening on ${host}:${port}${maxItems !== undefined ? `, at most ${maxItems} items per job` : ''}`);
      const url = `s7://${urlHost(host)}:${port}?${REACH[profile].query}`;
      if (symbols) for (const line of servedBlocks(symbols)) say(line);
      say(`try: plcwire read "${url}" ${symbols ? tryByName(symbols, args) : REACH[profile].addresses}`);
      close = () => server.close();
      break;
    }
    case 'fetchwrite': {
      const single = args.flags.has('port') ? intFlag(args, 'port', 0, 0, 65535) : undefined;
      const symbols = symbolsFlag(args, 'source');
      const server = new FetchWriteServer({
        host,
        ...(single !== undefined
          ? { port: single }
          : { fetchPort: intFlag(args, 'fetch-port', 2000, 0, 65535), writePort: intFlag(args, 'write-port', 2001, 0, 65535) }),
        ...(symbols ? { symbols } : {}),
      });
      const ports = await listen(() => server.listen(), 'port');
      const query =
        ports.fetchPort === ports.writePort ? `port=${ports.fetchPort}` : `fetchPort=${ports.fetchPort}&writePort=${ports.writePort}`;
      say(`FETCH/WRITE simulator listening on ${host}: fetch ${ports.fetchPort}, write ${ports.writePort}`);
      if (symbols) for (const line of servedBlocks(symbols)) say(line);
      say(`try: plcwire read "fetchwrite://${urlHost(host)}?${query}" ${symbols ? tryByName(symbols, args) : 'DB1,INT0 MB0'}`);
      close = () => server.close();
      break;
    }
    case 'freeport': {
      if (args.lists.has('source')) throw new UsageError('--source builds data blocks: serve s7 or serve fetchwrite');
      const stations = parseStations(stringFlag(args, 'stations') ?? '5');
      const bus = new FreeportBus({ stations });
      const path = stringFlag(args, 'path');
      if (path !== undefined && args.flags.has('tcp')) throw new UsageError('give --path or --tcp, not both');
      if (path !== undefined) {
        const baudRate = intFlag(args, 'baud', 9600, 1, 1_000_000);
        if (!FREEPORT_BAUD_RATES.includes(baudRate)) throw new UsageError(`--baud must be one of ${FREEPORT_BAUD_RATES.join(', ')}`);
        await bus.attachSerial(path, { baudRate });
        say(`freeport stations ${stations.join(', ')} answering on ${path} at ${baudRate} baud`);
      } else if (args.flags.has('tcp')) {
        const port = await listen(() => bus.listenTcp({ host, port: intFlag(args, 'tcp', 4001, 0, 65535) }), 'tcp');
        say(`freeport stations ${stations.join(', ')} answering on tcp ${host}:${port}`);
        say(`try: plcwire read "freeport+tcp://${urlHost(host)}:${port}" ST${stations[0]},DWORD0`);
      } else {
        throw new UsageError('serve freeport needs --path <serial device> or --tcp <port>');
      }
      close = () => bus.close();
      break;
    }
    default:
      throw new UsageError(`serve needs a protocol: s7, fetchwrite or freeport`);
  }
  say('Ctrl-C stops.');
  await untilInterrupted(io);
  await close();
  return EXIT.OK;
}

/** The data blocks built from --source, one line each: what a client's block info will report. */
function servedBlocks(table: SymbolTable): string[] {
  return table.blocks.map((b) => `serving DB${b.db} "${b.name}" of ${b.length} bytes (${b.file})`);
}

/** The read command for the first elementary member of the sources, by name: `--symbols Tank.db --db Tank=1 '"Tank".Level'`. */
function tryByName(table: SymbolTable, args: ParsedArgs): string {
  const first = table.entries.find((e) => e.kind === 'elementary' && e.db !== null);
  const files = listFlag(args, 'source').map((f) => `--symbols ${shellWord(f)}`);
  const dbs = listFlag(args, 'db').map((d) => `--db ${shellWord(d)}`);
  return [...files, ...dbs, ...(first ? [shellWord(first.name)] : [])].join(' ');
}

/** A word a POSIX shell passes through unchanged: bare when it is plain, else in single quotes. */
function shellWord(text: string): string {
  return /^[\w.,:/=@+-]+$/.test(text) ? text : `'${text.replace(/'/g, `'\\''`)}'`;
}

/** A bind error in words: port 102 needs privileges on Linux. */
async function listen<R>(start: () => Promise<R>, flag: string): Promise<R> {
  try {
    return await start();
  } catch (err) {
    const e = err as NodeJS.ErrnoException;
    if (e.code === 'EACCES') throw new UsageError(`no permission to listen on that port (ports below 1024 need root): try --${flag} 10102`);
    if (e.code === 'EADDRINUSE') throw new UsageError(`that port is already in use: choose another with --${flag}`);
    throw err;
  }
}

function loadLayout(file: string | undefined): MemoryLayout | undefined {
  if (file === undefined) return undefined;
  const text = readInputFile(file).toString('utf8');
  try {
    return JSON.parse(text) as MemoryLayout;
  } catch (err) {
    throw new UsageError(`--layout ${file} is not JSON: ${(err as Error).message}`);
  }
}

function parseStations(text: string): number[] {
  const stations = text.split(',').map((s) => s.trim());
  return stations.map((s) => {
    if (!/^\d+$/.test(s) || Number(s) > 255) throw new UsageError(`--stations: "${s}" is not a station address 0..255`);
    return Number(s);
  });
}

function urlHost(host: string): string {
  return host.includes(':') ? `[${host}]` : host;
}
