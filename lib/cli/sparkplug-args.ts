/**
 * The command line of `plcwire sparkplug`: brokers, the edge node's ids and
 * its devices, checked before anything connects, each mistake a UsageError
 * that names the option and the value (exit code 2).
 *
 * `--device NAME=<url>` names a Sparkplug device and its PLC; `--tags NAME:t1,t2`
 * and `--writable NAME:t1,t2` give that device's tags (symbols or addresses,
 * each one a metric of the same name) and those a host may write with DCMD.
 * A device without --tags publishes every tag of the symbol table (--symbols
 * files, compiled with their --db numbers) or, on s7plus://, of the PLC's
 * own browse. `--alarms NAME` adds the PLC's alarms as the device's
 * `Alarms/…` metrics (lib/sparkplug/alarms.ts), and `--writable
 * NAME:Alarms/Acknowledge` lets a host acknowledge them.
 */
import * as fs from 'node:fs';
import { driverOf, schemesOffering } from '../drivers';
import { ALARM_METRICS } from '../sparkplug/alarms';
import { parseUrl, type Endpoint } from '../url';
import type * as mqtt from 'mqtt';
import { intFlag, listFlag, stringFlag, UsageError, type ParsedArgs } from './args';
import { brokerUrl, MQTT_FLAGS, mqttOptions } from './sparkplug-mqtt';

export const SPARKPLUG_FLAGS = [
  'broker',
  'group',
  'node',
  'device',
  'tags',
  'writable',
  'alarms',
  'primary-host',
  'state-dir',
  'buffer',
  'buffer-dir',
  ...MQTT_FLAGS,
];

/** One --device with its --tags and --writable. */
export interface SparkplugCliDevice {
  name: string;
  url: string;
  endpoint: Endpoint;
  /** The tags given with --tags, in order; undefined: every tag the symbols or the PLC's browse name. */
  tags?: string[];
  writable: string[];
  /** --alarms NAME: the PLC's alarms as the device's `Alarms/…` metrics. */
  alarms: boolean;
}

export interface SparkplugCliOptions {
  brokers: string[];
  /** The broker login and TLS (lib/cli/sparkplug-mqtt.ts). */
  mqtt: mqtt.IClientOptions;
  group: string;
  node: string;
  devices: SparkplugCliDevice[];
  primaryHost?: string;
  interval: number;
  stateDir?: string;
  buffer: number;
  /** --buffer-dir: store-and-forward also kept on disk there, so a restarted edge node forwards it. */
  bufferDir?: string;
}

/** The default poll interval (ms) and store-and-forward bound (messages). */
const SPARKPLUG_DEFAULTS = Object.freeze({ interval: 1000, buffer: 10_000 });

/**
 * A Sparkplug id (group, edge node, device, host): UTF-8 text without the MQTT
 * separators and wildcards "/", "+", "#" (Sparkplug 3.0, section 4.1.1 "Topic Namespace Elements").
 */
function sparkplugId(flag: string, value: string | undefined): string {
  if (value === undefined || value === '') throw new UsageError(`--${flag} needs a value`);
  const bad = /[/+#]/.exec(value);
  if (bad) throw new UsageError(`--${flag} ${JSON.stringify(value)}: a Sparkplug id cannot hold "${bad[0]}"`);
  return value;
}

/** The --device a NAME of --tags, --writable or --alarms names. */
function deviceNamed(flag: string, raw: string, name: string, devices: ReadonlyMap<string, SparkplugCliDevice>): SparkplugCliDevice {
  const device = devices.get(name);
  if (!device)
    throw new UsageError(`--${flag} ${JSON.stringify(raw)}: no --device ${name}=<url> (devices: ${[...devices.keys()].join(', ')})`);
  return device;
}

/** `NAME:t1,t2` of --tags/--writable: the device and its tags. */
function deviceTags(flag: string, raw: string, devices: ReadonlyMap<string, SparkplugCliDevice>): [SparkplugCliDevice, string[]] {
  const colon = raw.indexOf(':');
  const example = `give DEVICE:tag,tag, e.g. --${flag} Line1:'"Tank".Level',MW4`;
  if (colon <= 0) throw new UsageError(`--${flag} ${JSON.stringify(raw)}: ${example}`);
  const device = deviceNamed(flag, raw, raw.slice(0, colon), devices);
  const tags = raw
    .slice(colon + 1)
    .split(',')
    .map((t) => t.trim());
  if (tags.some((t) => t === '')) throw new UsageError(`--${flag} ${JSON.stringify(raw)}: an empty tag; ${example}`);
  return [device, tags];
}

export function sparkplugOptions(args: ParsedArgs): SparkplugCliOptions {
  const brokers = listFlag(args, 'broker').map(brokerUrl);
  if (brokers.length === 0) throw new UsageError('give at least one --broker mqtt://host:1883');
  const group = sparkplugId('group', stringFlag(args, 'group'));
  const node = sparkplugId('node', stringFlag(args, 'node'));
  const devices = new Map<string, SparkplugCliDevice>();
  for (const raw of listFlag(args, 'device')) {
    const eq = raw.indexOf('=');
    if (eq <= 0) throw new UsageError(`--device ${JSON.stringify(raw)}: give NAME=<plc url>, e.g. --device Line1=s7://192.168.0.1`);
    const name = sparkplugId('device', raw.slice(0, eq));
    if (devices.has(name)) throw new UsageError(`--device ${name} is given twice`);
    const url = raw.slice(eq + 1);
    devices.set(name, { name, url, endpoint: parseUrl(url), writable: [], alarms: false });
  }
  if (devices.size === 0) throw new UsageError('give at least one --device NAME=<plc url>');
  for (const raw of listFlag(args, 'tags')) {
    const [device, tags] = deviceTags('tags', raw, devices);
    device.tags = [...(device.tags ?? []), ...tags];
  }
  for (const raw of listFlag(args, 'alarms')) {
    const device = deviceNamed('alarms', raw, raw, devices);
    if (!driverOf(device.endpoint).alarms)
      throw new UsageError(
        `--alarms ${raw}: its PLC is reached over ${device.endpoint.protocol}://, which reports no alarms (${schemesOffering('alarms')} do)`,
      );
    device.alarms = true;
  }
  for (const raw of listFlag(args, 'writable')) {
    const [device, tags] = deviceTags('writable', raw, devices);
    for (const t of tags) {
      if (t === ALARM_METRICS.acknowledge) {
        if (!device.alarms)
          throw new UsageError(`--writable ${device.name}:${t}: the device publishes no alarms; give --alarms ${device.name} as well`);
        continue;
      }
      if (device.tags && !device.tags.includes(t))
        throw new UsageError(`--writable ${device.name}:${t}: "${t}" is not one of the device's --tags (${device.tags.join(', ')})`);
    }
    device.writable.push(...tags);
  }
  const primaryHost = args.flags.has('primary-host') ? sparkplugId('primary-host', stringFlag(args, 'primary-host')) : undefined;
  return {
    brokers,
    mqtt: mqttOptions(args, brokers),
    group,
    node,
    devices: [...devices.values()],
    primaryHost,
    interval: intFlag(args, 'interval', SPARKPLUG_DEFAULTS.interval, 10, 3_600_000),
    stateDir: stringFlag(args, 'state-dir'),
    buffer: intFlag(args, 'buffer', SPARKPLUG_DEFAULTS.buffer, 0, 10_000_000),
    ...bufferDir(args),
  };
}

/** --buffer-dir DIR: an existing directory this process may write (checked now, not at the first outage). */
function bufferDir(args: ParsedArgs): { bufferDir?: string } {
  if (!args.flags.has('buffer-dir')) return {};
  const dir = stringFlag(args, 'buffer-dir');
  if (!dir) throw new UsageError('--buffer-dir needs a directory');
  let stat: fs.Stats;
  try {
    stat = fs.statSync(dir);
  } catch {
    throw new UsageError(`--buffer-dir ${JSON.stringify(dir)}: no such directory`);
  }
  if (!stat.isDirectory()) throw new UsageError(`--buffer-dir ${JSON.stringify(dir)}: not a directory`);
  try {
    fs.accessSync(dir, fs.constants.W_OK | fs.constants.X_OK);
  } catch {
    throw new UsageError(`--buffer-dir ${JSON.stringify(dir)}: this process may not write there`);
  }
  return { bufferDir: dir };
}
