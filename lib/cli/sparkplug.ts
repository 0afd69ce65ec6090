/**
 * `plcwire sparkplug`: a headless Sparkplug B edge node (lib/sparkplug/edge-node.ts)
 * for a container or a service. Each --device is a PLC whose tags are its
 * metrics; the command runs until Ctrl-C or SIGTERM, then publishes NDEATH,
 * disconnects and closes every PLC (exit code 130). What happens goes to
 * stderr, one line each: the session (broker, bdSeq), waiting for the primary
 * host, a PLC lost and back, a refused or done write or acknowledgement, its
 * alarm service failing, dropped buffered data.
 */
import { createClient, type AnyClient } from '../connect';
import { driverOf } from '../drivers';
import type { PlcError } from '../errors';
import { ALARM_METRICS } from '../sparkplug/alarms';
import { SparkplugEdgeNode } from '../sparkplug/edge-node';
import type { EdgeNodeStatus } from '../sparkplug/options';
import type { SparkplugDeviceOptions } from '../sparkplug/device';
import type { SymbolTable } from '../symbols/model';
import { endpointName } from '../url';
import { UsageError, type ParsedArgs } from './args';
import { EXIT, untilInterrupted, withClient, type CliIo } from './io';
import { passwordOption } from './s7plus';
import { sparkplugOptions, type SparkplugCliDevice } from './sparkplug-args';
import { symbolOptions } from './symbols';

/**
 * The metrics of a device without --tags: every elementary tag of `table`
 * (an array as one metric, not its elements), by name.
 */
function tagsOfTable(table: SymbolTable): string[] {
  return table.entries.filter((e) => e.dataType !== undefined && !/\[[^\]]*\]$/.test(e.name)).map((e) => e.name);
}

/** The device's tags: --tags, else the --symbols table's, else (s7plus://) the PLC's own browse. */
async function deviceTags(device: SparkplugCliDevice, client: AnyClient, table: SymbolTable | undefined, io: CliIo): Promise<string[]> {
  if (device.tags) return device.tags;
  const driver = driverOf(device.endpoint);
  if (driver.browse) {
    const browsed = await withClient(client, io, (c) => driver.browse!(c, { signal: io.signal }));
    return tagsOfTable(browsed);
  }
  if (table) return tagsOfTable(table);
  throw new UsageError(`--device ${device.name}: give its tags with --tags ${device.name}:<tag>,... or --symbols files that name them`);
}

function describe(status: EdgeNodeStatus, primaryHost: string | undefined): string {
  const bdSeq = status.bdSeq === undefined ? '' : ` (bdSeq ${status.bdSeq})`;
  switch (status.state) {
    case 'connecting':
      return `connecting to ${status.broker ?? 'the broker'}${bdSeq}`;
    case 'waiting-for-host':
      return `connected to ${status.broker ?? 'the broker'}${bdSeq}; waiting for the primary host ${primaryHost ?? ''} to be online`;
    case 'online':
      return `online on ${status.broker ?? 'the broker'}${bdSeq}: births sent`;
    default:
      return 'stopped';
  }
}

export async function sparkplug(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  if (rest.length > 0) throw new UsageError(`unexpected argument "${rest[0]}" (sparkplug takes options only)`);
  const options = sparkplugOptions(args);
  const { table, options: symbolConnect } = symbolOptions(args);
  const report = (line: string) => io.stderr.write(`plcwire: ${line}\n`);
  const clients: AnyClient[] = [];
  let node: SparkplugEdgeNode | undefined;
  try {
    const devices: SparkplugDeviceOptions[] = [];
    for (const d of options.devices) {
      const byAddress = !driverOf(d.endpoint).browse;
      const client = createClient(d.endpoint, { ...(byAddress ? symbolConnect : {}), ...passwordOption(d.endpoint, args) });
      clients.push(client);
      const tags = await deviceTags(d, client, byAddress ? table : undefined, io);
      if (io.signal.aborted) return EXIT.INTERRUPTED;
      devices.push({
        name: d.name,
        client,
        tags: Object.fromEntries(tags.map((t) => [t, t])),
        writable: d.writable,
        ...(d.alarms ? { alarms: true } : {}),
        ...(byAddress && table ? { symbols: table } : {}),
      });
      client.on('connected', () => report(`${d.name}: connected to ${endpointName(d.endpoint)}`));
      client.on('disconnected', (err: Error) => report(`${d.name}: disconnected: ${err.message}`));
      client.on('error', () => undefined); // reported through 'disconnected'
    }
    node = new SparkplugEdgeNode({
      brokers: options.brokers,
      group: options.group,
      node: options.node,
      devices,
      interval: options.interval,
      buffer: { count: options.buffer, ...(options.bufferDir !== undefined ? { dir: options.bufferDir } : {}) },
      ...(options.primaryHost !== undefined ? { primaryHost: options.primaryHost } : {}),
      ...(options.stateDir !== undefined ? { stateDir: options.stateDir } : {}),
      mqtt: options.mqtt,
    });
    node.on('status', (s: EdgeNodeStatus) => report(describe(s, options.primaryHost)));
    node.on('error', (err: PlcError) => report(err.message));
    node.on('command', (c: { device: string; metric: string; value: unknown }) =>
      report(
        c.metric === ALARM_METRICS.acknowledge
          ? `${c.device}: DCMD acknowledged alarm ${String(c.value)}`
          : `${c.device}: DCMD wrote ${c.metric} = ${JSON.stringify(c.value, (_k, v: unknown) => (typeof v === 'bigint' ? v.toString() : v))}`,
      ),
    );
    for (const c of clients) c.start();
    node.start();
    await untilInterrupted(io);
    return EXIT.INTERRUPTED;
  } finally {
    // NDEATH before the clean disconnect, then every PLC closed.
    await node?.stop();
    await Promise.all(clients.map((c) => c.close()));
  }
}
