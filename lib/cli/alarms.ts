/**
 * `plcwire alarms <url> [--json] [--watch]` and `plcwire ack <url> <id>
 * [--yes]`: a PLC's alarms through its driver's alarms port (lib/drivers.ts,
 * lib/alarms/model.ts), never through a scheme. Acknowledging is an
 * operator's write: the URL's readOnly and allow-list refuse it before
 * connecting (exit 4), and a PLC that is not this machine needs --yes or a
 * "y" at the prompt, as `plcwire write` does.
 */
import { createClient, type AnyClient } from '../connect';
import { driverOf, schemesOffering } from '../drivers';
import { ackRefusal } from '../alarms/ack-guard';
import type { AlarmEvent, AlarmPort, AlarmSubscription } from '../alarms/model';
import { alarmLine, eventLine, parseAlarmId, plainAlarm, plainEvent } from '../alarms/show';
import { abortError, isLinkError, PlcError } from '../errors';
import { endpointName, isLoopback, parseUrl, type Endpoint } from '../url';
import { UsageError, stringFlag, withTimeout, type ParsedArgs } from './args';
import { EXIT, confirm, untilInterrupted, withClient, type CliIo } from './io';
import { passwordOption } from './s7plus';
import { toJson } from './values';

/** The options of `alarms` and `ack` beside the shared ones (--json, --yes, --timeout, --password-file). */
export const ALARM_VALUE_FLAGS = ['language'];
export const ALARM_BOOL_FLAGS = ['watch', 'mode', 'diagnostics'];

/** The endpoint of `alarms`/`ack` (--timeout applied). */
function alarmEndpoint(url: string | undefined, command: string, args: ParsedArgs): Endpoint {
  const offered = schemesOffering('alarms');
  if (url === undefined) throw new UsageError(`${command} needs ${offered === '' ? 'a PLC URL' : `an ${offered} URL`}`);
  return withTimeout(parseUrl(url), args);
}

/** The alarms port of the endpoint's driver; a protocol without alarms is a usage error (nothing sent). */
function alarmPort(endpoint: Endpoint, command: string): AlarmPort<AnyClient> {
  const port = driverOf(endpoint).alarms;
  if (port) return port;
  const offered = schemesOffering('alarms');
  throw new UsageError(
    offered === ''
      ? `${command}: ${endpoint.protocol}:// has no alarms (no protocol of this build serves them)`
      : `${command}: ${endpoint.protocol}:// has no alarms; they are served over ${offered} (S7-300/400 and S7-1200/1500)`,
  );
}

/** The language of the texts (`--language de-DE`), else the PLC's first. */
function languageOf(args: ParsedArgs): string | undefined {
  if (args.flags.has('language') && stringFlag(args, 'language') === undefined) throw new UsageError('--language needs a language');
  return stringFlag(args, 'language');
}

/** `plcwire alarms <url> [--json] [--watch] [--mode] [--diagnostics] [--language L]`. */
export async function alarms(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = alarmEndpoint(rest[0], 'alarms', args);
  if (rest.length > 1) throw new UsageError(`unexpected argument "${rest[1]}"`);
  languageOf(args); // checked before connecting
  const watching = args.flags.has('watch');
  for (const f of ['mode', 'diagnostics']) if (args.flags.has(f) && !watching) throw new UsageError(`--${f} goes with --watch`);
  const port = alarmPort(endpoint, 'alarms');
  return alarmsOn(createClient(endpoint, passwordOption(endpoint, args)), port, args, io);
}

/** `plcwire alarms` once its command line is checked: `client` not yet connected, `port` its driver's (or a stand-in). */
export async function alarmsOn(client: AnyClient, port: AlarmPort<AnyClient>, args: ParsedArgs, io: CliIo): Promise<number> {
  const language = stringFlag(args, 'language');
  if (args.flags.has('watch')) return watchAlarms(client, port, args, io, language);
  const active = await withClient(client, io, (c) => port.list(c, { signal: io.signal }));
  if (args.flags.has('json')) io.stdout.write(`${toJson(active.map(plainAlarm))}\n`);
  else if (active.length === 0) io.stderr.write(`plcwire: no active alarms on ${endpointName(client.endpoint)}\n`);
  else for (const a of active) io.stdout.write(`${alarmLine(a, language)}\n`);
  return EXIT.OK;
}

/**
 * Connects, subscribes and prints every event until Ctrl-C (exit 130). After
 * a link loss the client reconnects and subscribes again by itself; the
 * subscription then reports what came or went while the link was down.
 * A refusal of the subscription itself (the CPU does not serve alarms) ends
 * the command with its error.
 */
async function watchAlarms(client: AnyClient, port: AlarmPort<AnyClient>, args: ParsedArgs, io: CliIo, language: string | undefined) {
  const json = args.flags.has('json');
  const report = (line: string) => io.stderr.write(`plcwire: ${line}\n`);
  const print = (e: AlarmEvent) => io.stdout.write(`${json ? toJson(plainEvent(e)) : eventLine(e, language)}\n`);
  const options = { mode: args.flags.has('mode'), diagnostics: args.flags.has('diagnostics'), signal: io.signal };
  let sub: AlarmSubscription | undefined;
  try {
    sub = await withLiveClient(client, io, () => port.subscribe(client, options, print));
  } catch (err) {
    await client.close();
    throw err;
  }
  const name = endpointName(client.endpoint);
  client.on('disconnected', (err: Error) => report(`disconnected from ${name}: ${err.message}`));
  client.on('reconnecting', (e: { delay: number }) => report(`reconnecting in ${(e.delay / 1000).toFixed(1)} s`));
  client.on('error', () => {}); // reported through 'disconnected'/'reconnecting'
  sub.on('lost', (err: PlcError) => report(`alarm subscription lost: ${err.message}`));
  sub.on('active', () => report(`subscribed to the alarms of ${name} again`));
  sub.on('error', (err: PlcError) => report(`alarm subscription: ${err.message}`));
  report(`subscribed to the alarms of ${name}; ${sub.active.length} active (Ctrl-C ends)`);
  try {
    await untilInterrupted(io);
  } finally {
    await sub.close().catch(() => undefined);
    await client.close();
  }
  return EXIT.INTERRUPTED;
}

/** Connects `client` (a first failure is the command's: exit 3) and runs `work` on it, leaving it open; Ctrl-C aborts. */
async function withLiveClient<R>(client: AnyClient, io: CliIo, work: () => Promise<R>): Promise<R> {
  const onAbort = () => void client.close();
  io.signal.addEventListener('abort', onAbort, { once: true });
  try {
    await client.connect();
    return await work();
  } catch (err) {
    if (io.signal.aborted) throw abortError('alarms --watch', io.signal);
    throw err;
  } finally {
    io.signal.removeEventListener('abort', onAbort);
  }
}

/** `plcwire ack <url> <id> [--yes]`: acknowledges one alarm; prints `alarm <id> acknowledged` once the PLC confirmed it. */
export async function ack(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const endpoint = alarmEndpoint(rest[0], 'ack', args);
  if (rest[1] === undefined) throw new UsageError('ack needs the id of the alarm (as plcwire alarms prints it)');
  if (rest.length > 2) throw new UsageError(`unexpected argument "${rest[2]}"`);
  let id: number;
  try {
    id = parseAlarmId(rest[1]);
  } catch (err) {
    throw new UsageError((err as Error).message);
  }
  // Refused by the URL before anything is sent, with the words the client would use.
  const refusal = ackRefusal(id, endpoint.readOnly, endpoint.allow);
  if (refusal) throw refusal;
  const port = alarmPort(endpoint, 'ack');
  if (!isLoopback(endpoint) && !args.flags.has('yes')) {
    if (!io.stdin.isTTY) {
      throw new PlcError(
        'WRITE_NOT_ALLOWED',
        `refusing to acknowledge alarm ${id} on ${endpointName(endpoint)} (not this machine) without --yes when standard input is not a terminal`,
      );
    }
    const ok = await confirm(io, `acknowledge alarm ${id} on ${endpointName(endpoint)}? [y/N] `);
    if (!ok) throw new PlcError('WRITE_NOT_ALLOWED', 'acknowledgement cancelled');
  }
  return ackOn(createClient(endpoint, passwordOption(endpoint, args)), port, id, args, io);
}

/** `plcwire ack` once its command line is checked and allowed: `client` not yet connected, `port` its driver's (or a stand-in). */
export async function ackOn(client: AnyClient, port: AlarmPort<AnyClient>, id: number, args: ParsedArgs, io: CliIo): Promise<number> {
  try {
    await withClient(client, io, (c) => port.acknowledge(c, id, { signal: io.signal }));
  } catch (err) {
    // The PLC's refusal (no such alarm, nothing to acknowledge) names the alarm; a link error keeps its own words.
    if (err instanceof PlcError && !isLinkError(err) && !err.message.includes(String(id))) {
      throw new PlcError(err.code, `alarm ${id}: ${err.message}`, { cause: err, tag: `ALARM${id}` });
    }
    throw err;
  }
  if (args.flags.has('json')) io.stdout.write(`${toJson({ id, acknowledged: true })}\n`);
  else io.stdout.write(`alarm ${id} acknowledged\n`);
  return EXIT.OK;
}
