/**
 * One Sparkplug device of an edge node: a PLC client and its tags as metrics
 * (name, alias, datatype, address), the last value and quality of each, and
 * report by exception: what changed since the last report, beyond a metric's
 * deadband (Sparkplug 3.0, section 5.7 "Edge Node NDATA and NCMD messages":
 * data messages carry only changed metrics). No MQTT here: the edge node
 * (lib/sparkplug/edge-node.ts) publishes what this returns.
 */
import { PlcError, type TagResult } from '../errors';
import type { SymbolTable } from '../symbols/model';
import type { DataTypeName, PlcClient, PlcValue, PreparedRead } from '../types';
import { ALARM_METRICS, DeviceAlarms, type SparkplugAlarmOptions } from './alarms';
import { DataType, type DataTypeId } from './datatypes';
import type { SparkplugMetric } from './model';
import { datatypeOfAddress, datatypeOfEntry, datatypeOfPlcType, qualityOf } from './types';

/** A device as the edge node's options give it. */
export interface SparkplugDeviceOptions {
  /** The Sparkplug device id (no "/", "+", "#"). */
  name: string;
  /** The PLC's client (from connect() or createClient()); the edge node reads and writes through it, never closes it. */
  client: PlcClient;
  /** Metric name → the tag that feeds it: an address (`DB1.DBD4:REAL`) or a symbol the client's symbol table knows. */
  tags: Readonly<Record<string, string>>;
  /**
   * Metric names a host may write with DCMD (each still passes the client's read-only/allow-list guard);
   * `Alarms/Acknowledge` lets a host acknowledge the PLC's alarms (with `alarms`).
   */
  writable?: readonly string[];
  /**
   * The PLC's alarms as the device's `Alarms/…` metrics (lib/sparkplug/alarms.ts), fed by its pushes:
   * true, or what to receive beside the alarms. Its driver must have an alarms port.
   */
  alarms?: boolean | SparkplugAlarmOptions;
  /** The symbol table the client reads names with, so metrics named by symbol get their datatypes from it. */
  symbols?: SymbolTable;
  /** Datatype of a metric whose tag is a name without a symbol table here (else taken from the first value read). */
  types?: Readonly<Record<string, DataTypeId>>;
}

/** One metric of a device. */
export interface MetricDefinition {
  readonly name: string;
  readonly alias: number;
  readonly address: string;
  /** Undefined until known: from the address, the symbol table, the options, or else the first good value read. */
  datatype: DataTypeId | undefined;
  readonly writable: boolean;
  readonly deadband: number;
  /** `Alarms/Acknowledge`: a DCMD acknowledges the alarm whose id it sends (no tag). */
  readonly acknowledge?: true;
}

/** What a device tells its edge node between polls: its alarms changed, or its alarm service failed. */
export interface DeviceHooks {
  alarmsChanged(): void;
  error(error: PlcError): void;
}

interface Sample {
  value: PlcValue | null;
  good: boolean;
  timestamp: number;
}

export class SparkplugDevice {
  readonly name: string;
  readonly client: PlcClient;
  readonly metrics: readonly MetricDefinition[];
  private readonly byName = new Map<string, MetricDefinition>();
  private readonly byAlias = new Map<number, MetricDefinition>();
  /** The values last reported (in a birth or a data message): what changes are measured against. */
  private readonly reported = new Map<string, Sample>();
  /** The values last read. */
  private readonly current = new Map<string, Sample>();
  private readonly prepared: PreparedRead;
  /** The PLC's alarms as metrics, when the options ask for them. */
  readonly alarms: DeviceAlarms | undefined;
  private readonly last: number;

  /** `firstAlias`: aliases are unique across the edge node, so each device starts where the one before ended. */
  constructor(
    options: SparkplugDeviceOptions,
    firstAlias: number,
    deadbands: Readonly<Record<string, number>> = {},
    hooks: DeviceHooks = { alarmsChanged: () => undefined, error: () => undefined },
  ) {
    this.name = options.name;
    this.client = options.client;
    const writable = new Set(options.writable ?? []);
    for (const w of writable) {
      if (w === ALARM_METRICS.acknowledge && options.alarms) continue;
      if (!(w in options.tags))
        throw new PlcError('INVALID_VALUE', `device ${options.name}: writable metric "${w}" is not one of its tags`, { tag: w });
    }
    const names = Object.keys(options.tags);
    if (names.length === 0) throw new PlcError('INVALID_VALUE', `device ${options.name} has no tags`);
    this.metrics = names.map((name, i) => {
      const address = options.tags[name]!;
      const deadband = deadbands[name] ?? 0;
      if (!(deadband >= 0))
        throw new PlcError('INVALID_VALUE', `device ${options.name}: the deadband of "${name}" must be a number ≥ 0`, { tag: name });
      const def: MetricDefinition = {
        name,
        alias: firstAlias + i,
        address,
        datatype: datatypeFor(name, address, options),
        writable: writable.has(name),
        deadband,
      };
      this.byName.set(name, def);
      this.byAlias.set(def.alias, def);
      return def;
    });
    this.last = firstAlias + names.length;
    if (options.alarms) {
      this.alarms = new DeviceAlarms(
        this.name,
        this.client,
        options.alarms === true ? {} : options.alarms,
        this.last,
        () => hooks.alarmsChanged(),
        (e) => hooks.error(e),
      );
      for (const a of this.alarms.metrics) {
        const def: MetricDefinition = {
          name: a.name,
          alias: a.alias,
          address: '',
          datatype: a.datatype,
          writable: a.name === ALARM_METRICS.acknowledge && writable.has(a.name),
          deadband: 0,
          ...(a.name === ALARM_METRICS.acknowledge ? { acknowledge: true as const } : {}),
        };
        this.byName.set(a.name, def);
        this.byAlias.set(a.alias, def);
      }
      this.last += this.alarms.metrics.length;
    }
    this.prepared = this.client.prepare(this.metrics.map((m) => m.address));
  }

  /** The next alias after this device's. */
  get endAlias(): number {
    return this.last;
  }

  /** Whether a host may write any of its metrics (the edge node then subscribes its DCMD topic). */
  get commandable(): boolean {
    return [...this.byName.values()].some((m) => m.writable);
  }

  metric(ref: { name?: string; alias?: number | bigint }): MetricDefinition | undefined {
    if (ref.name !== undefined) return this.byName.get(ref.name);
    return ref.alias === undefined ? undefined : this.byAlias.get(Number(ref.alias));
  }

  /** Reads every tag; rejects (with the client's error) when nothing could be read: the PLC is not reachable. */
  async poll(now = Date.now()): Promise<void> {
    const results = await this.prepared.readDetailed();
    this.take(results as Record<string, TagResult<PlcValue>>, now);
  }

  /** Takes values from a read or a push: `results` by address. */
  take(results: Readonly<Record<string, TagResult<PlcValue>>>, now = Date.now()): void {
    for (const m of this.metrics) {
      const r = results[m.address];
      if (!r) continue;
      if (r.ok && m.datatype === undefined) m.datatype = inferDatatype(r.value);
      this.current.set(m.name, r.ok ? { value: r.value, good: true, timestamp: now } : { value: null, good: false, timestamp: now });
    }
  }

  /** Whether every metric has a value (or a bad quality) to be born with. */
  get complete(): boolean {
    return this.metrics.every((m) => this.current.has(m.name) && m.datatype !== undefined) && (this.alarms?.settled ?? true);
  }

  /** The DBIRTH's metrics: every one, by name and alias, with its datatype, timestamp and current value. */
  birth(): SparkplugMetric[] {
    const tags = this.metrics.map((m) => {
      const s = this.current.get(m.name)!;
      this.reported.set(m.name, s);
      return { ...metricOf(m, s), name: m.name };
    });
    return this.alarms ? [...tags, ...this.alarms.birth()] : tags;
  }

  /** The metrics that changed since the last report (beyond their deadband), by alias; marks them reported. */
  changes(): SparkplugMetric[] {
    const out: SparkplugMetric[] = [];
    for (const m of this.metrics) {
      const s = this.current.get(m.name);
      if (!s || m.datatype === undefined) continue;
      const last = this.reported.get(m.name);
      if (last && !changed(last, s, m.deadband)) continue;
      this.reported.set(m.name, s);
      out.push(metricOf(m, s));
    }
    if (this.alarms) out.push(...this.alarms.changes());
    return out;
  }

  /** Whether values were reported (born) before: changes since then are worth keeping while there is no session. */
  get hasReported(): boolean {
    return this.reported.size > 0;
  }

  /** Forgets what was reported, so the next birth sends everything anew. */
  forgetReported(): void {
    this.reported.clear();
  }

  /** Ends the read and the alarm subscription (the client stays open: it is the caller's). */
  async close(): Promise<void> {
    this.prepared.close();
    await this.alarms?.close();
  }
}

function metricOf(m: MetricDefinition, s: Sample): SparkplugMetric {
  const quality = s.good ? undefined : qualityOf({ ok: false, error: new PlcError('PLC_ERROR', 'bad') });
  return {
    alias: m.alias,
    timestamp: s.timestamp,
    datatype: m.datatype!,
    ...(s.good ? { value: s.value as SparkplugMetric['value'] } : { isNull: true, value: null }),
    ...(quality ? { properties: quality } : {}),
  };
}

function changed(last: Sample, now: Sample, deadband: number): boolean {
  if (last.good !== now.good) return true;
  if (!now.good) return false;
  const a = last.value;
  const b = now.value;
  if (typeof a === 'number' && typeof b === 'number') return deadband > 0 ? Math.abs(b - a) > deadband : !Object.is(a, b) && !(a === b);
  if (typeof a === 'bigint' && typeof b === 'bigint') return deadband > 0 ? Math.abs(Number(b - a)) > deadband : a !== b;
  return !sameValue(a, b);
}

function sameValue(a: unknown, b: unknown): boolean {
  if (a instanceof Date && b instanceof Date) return a.getTime() === b.getTime();
  if (Array.isArray(a) && Array.isArray(b)) return a.length === b.length && a.every((x, i) => sameValue(x, b[i]));
  return a === b || (Number.isNaN(a) && Number.isNaN(b));
}

function datatypeFor(name: string, address: string, options: SparkplugDeviceOptions): DataTypeId | undefined {
  const given = options.types?.[name];
  if (given !== undefined) return given;
  const entry = options.symbols?.lookup(address);
  if (entry) return datatypeOfEntry(entry);
  // The client's own address syntax (freeport's ST5,REAL0 is not an S7 address). Every client has the public
  // tag() of lib/client/base.ts, which PlcClient does not declare.
  const client = options.client as PlcClient & { tag?(address: string): { type?: DataTypeName; isArray?: boolean } };
  try {
    const tag = client.tag?.(address);
    if (tag?.type !== undefined) return datatypeOfPlcType(tag.type, tag.isArray === true);
  } catch {
    // not an address of its syntax: a name, below
  }
  try {
    return datatypeOfAddress(address);
  } catch {
    return undefined; // a name the client resolves: typed by its first value
  }
}

/** A datatype from a value, for a tag named without a symbol table here: numbers as Double (their PLC width is not known). */
function inferDatatype(value: PlcValue): DataTypeId {
  const first = Array.isArray(value) ? value[0] : value;
  const scalar: DataTypeId =
    typeof first === 'boolean'
      ? DataType.Boolean
      : typeof first === 'bigint'
        ? DataType.Int64
        : typeof first === 'string'
          ? DataType.String
          : first instanceof Date
            ? DataType.DateTime
            : DataType.Double;
  if (!Array.isArray(value)) return scalar;
  const arrays: Partial<Record<number, DataTypeId>> = {
    [DataType.Boolean]: DataType.BooleanArray,
    [DataType.Int64]: DataType.Int64Array,
    [DataType.String]: DataType.StringArray,
    [DataType.DateTime]: DataType.DateTimeArray,
    [DataType.Double]: DataType.DoubleArray,
  };
  return arrays[scalar]!;
}
