/**
 * The `plcwire` command line: read, write and watch any PLC by URL, and run
 * the simulators. Every failure is one readable line on stderr and an exit
 * code a script can switch on (see EXIT and the README's CLI reference).
 */
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { createClient, type AnyClient } from '../connect';
import { driverOf } from '../drivers';
import { NAME_HINT } from '../address/parse';
import { AddressError, PlcError, TagErrors, type TagResult } from '../errors';
import type { SymbolTable } from '../symbols/model';
import type { PlcData } from '../types';
import { validateValue, type TagShape } from '../values';
import { endpointName, isLoopback, parseUrl, type Endpoint } from '../url';
import { parseArgs, UsageError, intFlag, withTimeout, type ParsedArgs } from './args';
import { commandHelp } from './help';
import { EXIT, confirm, exitCode, fail, withClient, type CliIo } from './io';
import { serve, SERVE_FLAGS } from './serve';
import { realsShown } from '../symbols/reals';
import { reportLayout, structValueFromText, symbolOptions, symbols, SYMBOL_FLAGS } from './symbols';
import { browse, browsedValueFromText, isPlcName, passwordOption } from './s7plus';
import { subscriberOf, watchPushed } from './watch-push';
import { ack, alarms, ALARM_BOOL_FLAGS, ALARM_VALUE_FLAGS } from './alarms';
import { blocks, clock, cpu, diag, doctor, info, szl } from './system';
import { SPARKPLUG_FLAGS } from './sparkplug-args';
import { textForPeople, toJson, valueFromText, type TypedTag } from './values';

const USAGE = `usage:
  plcwire read  <url> <address|symbol>... [--symbols file]... [--db NAME=N]... [--strict-symbols] [--json] [--timeout ms]
  plcwire write <url> <address|symbol>=<value>... [--symbols file]... [--db NAME=N]... [--strict-symbols] [--yes] [--json] [--timeout ms]
  plcwire watch <url> <address|symbol>... [--symbols file]... [--db NAME=N]... [--strict-symbols] [--interval ms] [--cycle ms] [--json]
  plcwire symbols <file>... [--db NAME=N]... [--json | --csv]   (DB/UDT sources, symbol tables)
  plcwire browse <s7plus-url> [--password-file FILE] [--json | --csv]   (the PLC's own tags, optimized blocks too)
  plcwire info  <url> [--json]
  plcwire szl   <url> <id> [index] [--json]              (hex, e.g. 0x0011 0)
  plcwire diag  <url> [--max N] [--json]
  plcwire clock <url> [--set now|<ISO time>] [--yes] [--json]
  plcwire blocks <url> [TYPE [NUMBER]] [--json]          (OB, FB, FC, DB, SDB, SFC, SFB)
  plcwire cpu   <url> stop|start|cold-start [--yes] [--json]   (the URL needs control=true)
  plcwire alarms <url> [--watch [--mode] [--diagnostics]] [--language L] [--json]   (s7:// S7-300/400, s7plus:// S7-1200/1500)
  plcwire ack   <url> <alarm id> [--yes] [--json]        (an operator's write: readOnly and allow= refuse it)
  plcwire doctor <url> [address|symbol...] [--symbols file]... [--db NAME=N]... [--strict-symbols] [--json] [--timeout ms]
  plcwire serve s7 [--port 102] [--host 127.0.0.1] [--profile s7-1500|s7-1200|s7-300|s7-400|s7-200|logo] [--layout file.json] [--max-items N]
                   [--source Tank.db... --db Tank=1...] [--tls-cert cert.pem --tls-key key.pem] [--password-file FILE] [--alarms F]
  plcwire serve fetchwrite [--fetch-port 2000] [--write-port 2001] [--port N] [--host 127.0.0.1] [--source file... --db NAME=N...]
  plcwire serve freeport (--path <device> [--baud 9600] | --tcp <port> [--host 127.0.0.1]) [--stations 5,6]
  plcwire sparkplug --broker mqtt://host:1883 [--broker ...] --group G --node E --device NAME=<url> [--device ...]
                   [--symbols file --db NAME=N]... [--tags NAME:<tag>,...] [--writable NAME:<tag>,...] [--alarms NAME]...
                   [--primary-host H] [--interval ms] [--state-dir DIR] [--buffer N] [--buffer-dir DIR]   (a Sparkplug B edge node, each PLC a device)
  plcwire demo [--tls-dir DIR] [--port 10102] (the S7-1200's certificate kept between runs; demo --help: every port)
options: --debug prints stack traces; --help (-h) prints this text, plcwire <command> --help that command's;
      --version the package's version.
symbols: names as TIA writes them ('"Tank".Motor.Speed', Tank.Motor.Speed); a STRUCT reads as an object
      and is written as JSON ('"Tank".Motor={"Speed":1.5}'); --db numbers the blocks of TIA sources;
      a DB whose length in the PLC differs from the sources' is a warning, --strict-symbols refuses its names.
urls: s7://host?rack=0&slot=1  fetchwrite://host?fetchPort=2000&writePort=2001
      s7plus://host?fingerprint=<SHA-256 of the PLC's certificate>  (or ca=FILE; insecure=true for the bench)
password (s7plus:// only): PLCWIRE_PASSWORD or --password-file FILE (its first line); never in the URL or a flag
      freeport:///dev/ttyUSB0?baud=9600  freeport+tcp://host:4001
exit codes: 0 ok, 1 tag error, 2 usage/bad input, 3 connection, 4 write or control refused, 130 interrupted`;

const OWN_VALUE_FLAGS = ['timeout', 'interval', 'cycle', 'max', 'set', 'password-file', 'freeport-port'];
const VALUE_FLAGS = [...OWN_VALUE_FLAGS, ...SERVE_FLAGS, ...SYMBOL_FLAGS, ...SPARKPLUG_FLAGS];
const BOOL_FLAGS = ['json', 'csv', 'yes', 'debug', 'help', 'version', 'strict-symbols'];

export async function main(argv: readonly string[], io: CliIo): Promise<number> {
  let args: ParsedArgs;
  // -h is --help (before a `--`, after which everything is a positional).
  const end = argv.indexOf('--');
  const words = argv.map((a, i) => (a === '-h' && (end < 0 || i < end) ? '--help' : a));
  try {
    args = parseArgs(words, [...VALUE_FLAGS, ...ALARM_VALUE_FLAGS], [...BOOL_FLAGS, ...ALARM_BOOL_FLAGS]);
  } catch (err) {
    // `plcwire read --help` prints read's help even beside an option read does not know.
    const command = words.find((w) => !w.startsWith('-'));
    if (words.includes('--help') && command !== undefined && commandHelp(command)) {
      io.stdout.write(`${commandHelp(command)}\n`);
      return EXIT.OK;
    }
    return fail(io, err, false);
  }
  const debug = args.flags.has('debug');
  const [command, ...rest] = args.positionals;
  if (args.flags.has('version')) {
    io.stdout.write(`${packageVersion()}\n`);
    return EXIT.OK;
  }
  // `plcwire read --help`, `plcwire help read`: that command's usage, options and an example.
  const asked = command === 'help' ? rest[0] : args.flags.has('help') ? command : undefined;
  const help = asked === undefined ? undefined : commandHelp(asked);
  if (help !== undefined) {
    io.stdout.write(`${help}\n`);
    return EXIT.OK;
  }
  if (args.flags.has('help') || command === undefined || command === 'help') {
    io.stdout.write(`${USAGE}\n`);
    return command === undefined && !args.flags.has('help') ? EXIT.USAGE : EXIT.OK;
  }
  try {
    switch (command) {
      case 'read':
        return await read(rest, args, io);
      case 'write':
        return await write(rest, args, io);
      case 'watch':
        return await watch(rest, args, io);
      case 'info':
        return await info(rest, args, io);
      case 'szl':
        return await szl(rest, args, io);
      case 'diag':
        return await diag(rest, args, io);
      case 'clock':
        return await clock(rest, args, io);
      case 'blocks':
        return await blocks(rest, args, io);
      case 'cpu':
        return await cpu(rest, args, io);
      case 'doctor':
        return await doctor(rest, args, io);
      case 'symbols':
        return symbols(rest, args, io);
      case 'browse':
        return await browse(rest, args, io);
      case 'serve':
        return await serve(rest, args, io);
      case 'alarms':
        return await alarms(rest, args, io);
      case 'ack':
        return await ack(rest, args, io);
      case 'demo':
        return await (await import('./demo')).runDemo(rest, args, io);
      case 'sparkplug':
        return await (await import('./sparkplug')).sparkplug(rest, args, io);
      default:
        throw new UsageError(
          `unknown command "${command}" (read, write, watch, symbols, browse, info, szl, diag, clock, blocks, cpu, alarms, ack, doctor, serve, sparkplug, demo)`,
        );
    }
  } catch (err) {
    return fail(io, err, debug);
  }
}

/** The version of the package this command belongs to (its package.json, beside dist/). */
function packageVersion(): string {
  const pkg = JSON.parse(readFileSync(join(__dirname, '../../../package.json'), 'utf8')) as { version: string };
  return pkg.version;
}

function endpointArg(rest: string[], what: string): { endpoint: Endpoint; addresses: string[] } {
  const [url, ...addresses] = rest;
  if (url === undefined) throw new UsageError(`${what} needs a PLC url`);
  if (addresses.length === 0) throw new UsageError(`${what} needs at least one address`);
  return { endpoint: parseUrl(url), addresses };
}

/**
 * The client for read, write and watch: with --symbols it holds the table,
 * resolves the names and checks the layout (reported on stderr). Every
 * address and name is then checked before connecting (an unstarted client
 * holds nothing): a typo never costs a PLC connection; an unknown name is the
 * client's INVALID_ADDRESS with the closest names.
 */
function targetClient(
  endpoint: Endpoint,
  targets: readonly string[],
  args: ParsedArgs,
  io: CliIo,
): { client: AnyClient; table: SymbolTable | undefined } {
  const { table, options } = symbolOptions(args);
  let client: AnyClient;
  try {
    client = createClient(withTimeout(endpoint, args), { ...options, ...passwordOption(endpoint, args) });
  } catch (err) {
    // Freeport refuses a symbol table: a bad command line, nothing was sent.
    if (err instanceof PlcError && err.code === 'NOT_SUPPORTED') throw new UsageError(err.message);
    throw err;
  }
  for (const target of targets) {
    try {
      client.tag(target);
    } catch (err) {
      throw table ? err : withSymbolsHint(err, target);
    }
  }
  if (table) reportLayout(client, io, options.strictSymbols === true);
  return { client, table };
}

/**
 * A tag name given without --symbols: the library's error says it looks like
 * one; a second line says which options give the sources.
 */
function withSymbolsHint(err: unknown, target: string): unknown {
  if (!(err instanceof AddressError) || !err.message.endsWith(NAME_HINT)) return err;
  const block = /^"([^"]+)"|^([A-Za-z_]\w*)/.exec(target);
  const name = block?.[1] ?? block?.[2] ?? 'Tank';
  return new AddressError(
    target,
    err.problem,
    `${NAME_HINT}\nplcwire: give them with --symbols (and --db for TIA blocks), e.g. --symbols ${name}.db --db ${name}=1`,
  );
}

/**
 * With a table, the layout check of the connection, waited for so that its
 * warning is printed before the command ends (it is the check the client
 * starts on connect, shared, not a second one). Its failures are the
 * request's to tell.
 */
function layoutChecked(client: AnyClient, table: SymbolTable | undefined, io: CliIo): Promise<unknown> {
  return table ? client.checkLayout({ signal: io.signal }).catch(() => undefined) : Promise.resolve();
}

async function read(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const { endpoint, addresses } = endpointArg(rest, 'read');
  const json = args.flags.has('json');
  const { client, table } = targetClient(endpoint, addresses, args, io);
  const [results] = await withClient(client, io, (c) =>
    Promise.all([c.readDetailed<PlcData>(addresses, { signal: io.signal }), layoutChecked(c, table, io)]),
  );
  const values: Record<string, unknown> = {};
  const errors: PlcError[] = [];
  for (const address of addresses) {
    const r = results[address]!;
    if (r.ok) values[address] = realsShown(client, table, address, r.value);
    else {
      values[address] = null;
      errors.push(r.error);
    }
  }
  if (json) io.stdout.write(`${toJson(values)}\n`);
  else for (const a of addresses) if (values[a] !== null) io.stdout.write(`${a} = ${textForPeople(client, table, a, values[a])}\n`);
  for (const e of errors) io.stderr.write(`plcwire: ${e.message}\n`);
  return errors.length === 0 ? EXIT.OK : exitCode(new TagErrors(results));
}

async function write(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const { endpoint, addresses: assignments } = endpointArg(rest, 'write');
  const pairs = assignments.map((a) => {
    const eq = a.indexOf('=');
    if (eq <= 0) throw new UsageError(`"${a}" is not <address>=<value>`);
    return { address: a.slice(0, eq), text: a.slice(eq + 1) };
  });
  // Parse addresses, names and values before connecting: bad input never reaches the PLC.
  const { client, table } = targetClient(
    endpoint,
    pairs.map((p) => p.address),
    args,
    io,
  );
  const values: Record<string, unknown> = {};
  // Names of the PLC's own table (s7plus:// without sources): their types come with the browse, after connecting.
  const browsedNames: { address: string; text: string }[] = [];
  for (const { address, text } of pairs) {
    if (table === undefined && isPlcName(client, address)) {
      browsedNames.push({ address, text });
      continue;
    }
    const struct = structValueFromText(client, table, address, text);
    if (struct) {
      values[address] = struct.value;
      continue;
    }
    const tag = client.tag(address) as unknown as TypedTag & TagShape;
    values[address] = valueFromText(tag, text);
    validateValue(tag, values[address]);
  }
  if (!isLoopback(endpoint) && !args.flags.has('yes')) {
    if (!io.stdin.isTTY) {
      throw new PlcError(
        'WRITE_NOT_ALLOWED',
        `refusing to write to ${endpointName(endpoint)} (not this machine) without --yes when standard input is not a terminal`,
      );
    }
    const ok = await confirm(io, `write ${pairs.length} value(s) to ${endpointName(endpoint)}? [y/N] `);
    if (!ok) throw new PlcError('WRITE_NOT_ALLOWED', 'write cancelled');
  }
  // The layout check first: its warning comes before the values are sent.
  const results = await withClient(client, io, async (c) => {
    await layoutChecked(c, table, io);
    if (browsedNames.length > 0) {
      const browsed = await driverOf(c).browse!(c, { signal: io.signal }); // isPlcName: only a driver that browses has such names
      for (const { address, text } of browsedNames) values[address] = browsedValueFromText(browsed, address, text);
    }
    return c.writeDetailed(values, { signal: io.signal });
  });
  const errors = Object.values(results).filter((r) => !r.ok);
  if (args.flags.has('json')) {
    const out: Record<string, string> = {};
    for (const [a, r] of Object.entries(results)) out[a] = r.ok ? 'ok' : r.error.message;
    io.stdout.write(`${toJson(out)}\n`);
  } else {
    for (const [a, r] of Object.entries(results)) if (r.ok) io.stdout.write(`${a} = ${textForPeople(client, table, a, values[a])} ok\n`);
  }
  for (const r of Object.values(results)) if (!r.ok) io.stderr.write(`plcwire: ${r.error.message}\n`);
  if (errors.length === 0) return EXIT.OK;
  const written = Object.keys(results).filter((a) => results[a]!.ok);
  if (written.length === 0) return exitCode(new TagErrors(results));
  // Some values reached the PLC: say which, and never the exit code that means nothing was sent.
  const failed = Object.keys(results).filter((a) => !results[a]!.ok);
  io.stderr.write(`plcwire: partly written: ${written.join(', ')} written; ${failed.join(', ')} not written\n`);
  const code = exitCode(new TagErrors(results));
  return code === EXIT.USAGE ? EXIT.TAG_ERROR : code;
}

/**
 * Polls until Ctrl-C; prints a line per changed value (all values first).
 * Link loss is reported on stderr and the client reconnects by itself. On
 * s7plus:// the PLC reports the changes (watch-push.ts); only what cannot be
 * subscribed is polled.
 */
async function watch(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const { endpoint, addresses } = endpointArg(rest, 'watch');
  const interval = intFlag(args, 'interval', 1000, 10, 3_600_000);
  const cycle = intFlag(args, 'cycle', 100, 10, 3_600_000);
  const json = args.flags.has('json');
  const { client, table } = targetClient(endpoint, addresses, args, io); // bad addresses and unknown names fail here, before connecting
  const last = new Map<string, string>();
  const report = (line: string) => io.stderr.write(`plcwire: ${line}\n`);
  client.on('connected', () => report(`connected to ${endpointName(endpoint)}`));
  client.on('disconnected', (err: Error) => report(`disconnected: ${err.message}`));
  client.on('reconnecting', (e: { delay: number; error?: Error }) =>
    report(`reconnecting in ${(e.delay / 1000).toFixed(1)} s${e.error ? ` (${e.error.message})` : ''}`),
  );
  client.on('error', () => {}); // reported through 'disconnected'/'reconnecting'
  const print = (results: Record<string, TagResult<unknown>>) => {
    const changed: Record<string, unknown> = {};
    for (const [a, r] of Object.entries(results)) {
      const value = r.ok ? realsShown(client, table, a, r.value) : undefined;
      const text = r.ok ? textForPeople(client, table, a, value) : `error: ${r.error.message}`;
      if (last.get(a) === text) continue;
      last.set(a, text);
      if (r.ok) changed[a] = value;
      // A tag's error names it already (tagError); an error that does not is prefixed with the target.
      else report(r.error.tag === a ? r.error.message : `${a}: ${r.error.message}`);
    }
    if (Object.keys(changed).length > 0) {
      if (json) io.stdout.write(`${toJson({ time: new Date().toISOString(), values: changed })}\n`);
      else
        for (const [a, v] of Object.entries(changed))
          io.stdout.write(`${new Date().toISOString()} ${a} = ${textForPeople(client, table, a, v)}\n`);
    }
  };
  const readAndPrint = async (list: readonly string[]) => {
    if (client.state !== 'connected' || list.length === 0) return;
    try {
      const results = await client.readDetailed<PlcData>(list, { signal: io.signal });
      print(Object.fromEntries(list.map((a) => [a, results[a]!])));
    } catch (err) {
      if (!io.signal.aborted) report((err as Error).message);
    }
  };
  let polled: readonly string[] = addresses;
  // A tag that falls back to polling is read at once, then with the others every interval.
  const poll = (tags: readonly string[]) => {
    const fresh = tags.filter((t) => !polled.includes(t));
    polled = addresses.filter((a) => tags.includes(a));
    void readAndPrint(fresh);
  };
  const subscribe = subscriberOf(client);
  const push = subscribe ? watchPushed(client, subscribe, addresses, { cycle, interval, report, print, poll }) : undefined;
  if (push) polled = [];
  client.start();
  try {
    while (!io.signal.aborted) {
      const started = Date.now();
      await readAndPrint(polled);
      await delay(Math.max(0, interval - (Date.now() - started)), io.signal);
    }
  } finally {
    await push?.stop();
    await client.close();
  }
  // It runs until stopped: Ctrl-C (or SIGTERM) is how it ends, and the exit code says so.
  return io.signal.aborted ? EXIT.INTERRUPTED : EXIT.OK;
}

function delay(ms: number, signal: AbortSignal): Promise<void> {
  return new Promise((resolve) => {
    if (signal.aborted) return resolve();
    const done = () => {
      clearTimeout(timer);
      signal.removeEventListener('abort', done);
      resolve();
    };
    const timer = setTimeout(done, ms);
    signal.addEventListener('abort', done, { once: true });
  });
}
