/** `plcwire serve <protocol>`: run a simulator until Ctrl-C; each protocol's entry in lib/drivers.ts starts its own. */
import { DRIVERS } from '../drivers';
import type { ServeFlags } from '../sim/serve';
import type { SymbolTable } from '../symbols/model';
import { orList } from '../values/text';
import { UsageError, intFlag, listFlag, stringFlag, type ParsedArgs } from './args';
import { readInputFile } from './files';
import { EXIT, untilInterrupted, type CliIo } from './io';
import { sourceFilesFlag, symbolsFlag } from './symbols';

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
  'tls-cert',
  'tls-key',
  'tls-dir',
  'password-file',
  'alarms',
];

export async function serve(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const [protocol, ...extra] = rest;
  if (extra.length > 0) throw new UsageError(`unexpected argument "${extra[0]}"`);
  const host = stringFlag(args, 'host') ?? '127.0.0.1';
  const say = (line: string) => io.stdout.write(`${line}\n`);
  const driver = protocol !== undefined && Object.hasOwn(DRIVERS, protocol) ? DRIVERS[protocol as keyof typeof DRIVERS] : undefined;
  if (!driver) throw new UsageError(`serve needs a protocol: ${orList(Object.keys(DRIVERS))}`);
  const flags: ServeFlags = {
    host,
    say,
    has: (flag) => args.flags.has(flag),
    string: (flag) => stringFlag(args, flag),
    int: (flag, fallback, min, max) => intFlag(args, flag, fallback, min, max),
    source: () => symbolsFlag(args, 'source'),
    sourceFiles: () => sourceFilesFlag(args, 'source'),
    sourcePaths: () => listFlag(args, 'source'),
    hasSource: () => args.lists.has('source'),
    tryRead: (url, table, s7plusUrl) => tryRead(args, url, table, s7plusUrl),
    usage: (message) => new UsageError(message),
    readFile: readInputFile,
    listen,
  };
  const served = await driver.serve(flags);
  say('Ctrl-C stops.');
  await untilInterrupted(io);
  await served.close();
  return EXIT.OK;
}

/**
 * The command that reads the first elementary member of the sources, by name:
 * over `url` with the sources when a read by address reaches it
 * (`read "s7://…" --symbols Tank.db --db Tank=1 '"Tank".Level'`); when every
 * member lies in an optimized block, over `s7plusUrl`, where the PLC's browse
 * gives the names (`read "s7plus://…?fingerprint=…" '"Tank".Phase'`); with
 * neither, `symbols`, which shows what the sources declare and why nothing
 * has an address.
 */
function tryRead(args: ParsedArgs, url: string, table: SymbolTable, s7plusUrl: string | undefined): string {
  const elementary = table.entries.filter((e) => e.kind === 'elementary' && e.db !== null);
  const byAddress = elementary.find((e) => e.address !== null);
  const sources = listFlag(args, 'source').map(shellWord);
  const dbs = listFlag(args, 'db').map((d) => `--db ${shellWord(d)}`);
  if (byAddress) return [`plcwire read "${url}"`, ...sources.map((f) => `--symbols ${f}`), ...dbs, shellWord(byAddress.name)].join(' ');
  if (s7plusUrl !== undefined && elementary[0]) return `plcwire read "${s7plusUrl}" ${shellWord(elementary[0].name)}`;
  return ['plcwire symbols', ...sources, ...dbs].join(' ');
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
