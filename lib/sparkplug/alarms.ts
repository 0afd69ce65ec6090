/**
 * A PLC's alarms as metrics of its Sparkplug device, fed by the PLC's own
 * pushes through its driver's alarms port (lib/drivers.ts, lib/alarms/model.ts:
 * ALARM_S/SQ/8/NOTIFY on S7-300/400, Program_Alarm on S7-1200/1500).
 *
 * A fixed set of metrics, not one per alarm: a CPU tells an alarm's id only
 * when it comes (neither generation lists the alarms a program could raise),
 * and a metric a DBIRTH did not name may not appear in DDATA
 * (tck-id-payloads-name-birth-data-requirement), so a metric per alarm would
 * need a new DBIRTH at each new id. Instead:
 *
 * - `Alarms/Active` (DataSet): the active alarms, a row each, sent whole when
 *   one of them changes;
 * - `Alarms/Active Count`, `Alarms/Unacknowledged Count` (Int32): what a host
 *   can put its own alarm on;
 * - `Alarms/Event` (String): every event the PLC reported, one value each,
 *   timestamped with the PLC's own time, as the JSON the CLI's --json and the
 *   alarms node give (lib/alarms/show.ts plainEvent);
 * - `Alarms/Acknowledge` (UInt32): a host writes an alarm id with DCMD, when
 *   the device's `writable` names it; the connection's read-only and allow
 *   list (ALARMS or ALARM<id>) still decide (lib/alarms/ack-guard.ts).
 *
 * While the subscription is not up (not yet, link lost, the CPU refused it)
 * the table and the counts are null with Quality BAD (section 6.4.10).
 */
import type { AlarmEvent, AlarmPort, AlarmSubscription, PlcAlarm } from '../alarms/model';
import { alarmCounts, alarmText, plainEvent } from '../alarms/show';
import { driverOf, schemesOffering } from '../drivers';
import { PlcError, refusedForGood, toPlcError } from '../errors';
import type { PlcClient } from '../types';
import { DataType, type DataTypeId } from './datatypes';
import { Quality, type DataSet, type SparkplugMetric } from './model';

/** What a device's alarm metrics carry beside the alarms (device option `alarms`). */
export interface SparkplugAlarmOptions {
  /** Also the CPU's operating-mode changes as `Alarms/Event` values (S7-300/400). Default false. */
  mode?: boolean;
  /** Also its diagnostic messages as `Alarms/Event` values. Default false. */
  diagnostics?: boolean;
  /** Languages of the texts (S7CommPlus); the first fills the table's Text column. */
  languages?: readonly string[];
}

/** The names of the alarm metrics. */
export const ALARM_METRICS = Object.freeze({
  active: 'Alarms/Active',
  activeCount: 'Alarms/Active Count',
  unacknowledged: 'Alarms/Unacknowledged Count',
  event: 'Alarms/Event',
  acknowledge: 'Alarms/Acknowledge',
});

/** The columns of `Alarms/Active`, and their datatypes. */
export const ALARM_COLUMNS = Object.freeze([
  ['Id', DataType.UInt32],
  ['Kind', DataType.String],
  ['Signal', DataType.UInt8],
  ['State', DataType.String],
  ['Acknowledged', DataType.Boolean],
  ['Priority', DataType.Int32],
  ['Time', DataType.DateTime],
  ['Text', DataType.String],
] as const satisfies readonly (readonly [string, DataTypeId])[]);

/** One alarm metric: its name, alias and datatype. */
export interface AlarmMetric {
  readonly name: string;
  readonly alias: number;
  readonly datatype: DataTypeId;
}

type Link = 'waiting' | 'up' | 'down' | 'refused';

/** How long after a failed subscription attempt (on a link that stayed up) the next one waits. */
const RETRY_MS = 10_000;

interface Pending {
  value: string;
  timestamp: number;
  /** Taken while the device was not born: sent as historical after its birth. */
  late: boolean;
}

export class DeviceAlarms {
  readonly metrics: readonly AlarmMetric[];
  private readonly port: AlarmPort<PlcClient>;
  private sub: AlarmSubscription | undefined;
  private opening = false;
  private closed = false;
  private link: Link = 'waiting';
  /** The first attempt ended (subscribed or failed): the device may be born, with BAD alarm metrics if it failed. */
  private tried = false;
  private readonly pending: Pending[] = [];
  private lastEvent: Pending | undefined;
  /** What the last report (birth or data) sent of the table and the counts, as a key. */
  private reported: string | undefined;
  private born = false;
  /** A retry after a failed attempt waits until then; the failure's message, told once. */
  private notBefore = 0;
  private lastError: string | undefined;
  private pendingReport: NodeJS.Immediate | undefined;

  constructor(
    private readonly device: string,
    private readonly client: PlcClient,
    private readonly options: SparkplugAlarmOptions,
    firstAlias: number,
    private readonly onChange: () => void,
    private readonly onError: (error: PlcError) => void,
  ) {
    const port = driverOf(client).alarms as AlarmPort<PlcClient> | undefined;
    if (!port) {
      throw new PlcError(
        'NOT_SUPPORTED',
        `device ${device}: a ${client.protocol} connection reports no alarms (${schemesOffering('alarms')} do)`,
      );
    }
    this.port = port;
    const names: [string, DataTypeId][] = [
      [ALARM_METRICS.active, DataType.DataSet],
      [ALARM_METRICS.activeCount, DataType.Int32],
      [ALARM_METRICS.unacknowledged, DataType.Int32],
      [ALARM_METRICS.event, DataType.String],
      [ALARM_METRICS.acknowledge, DataType.UInt32],
    ];
    this.metrics = names.map(([name, datatype], i) => ({ name, alias: firstAlias + i, datatype }));
  }

  /** Whether the device can be born: the first subscription attempt has ended. */
  get settled(): boolean {
    return this.tried;
  }

  /**
   * Subscribes when the client is connected and no subscription is held (the client itself renews one after
   * a reconnect). `retry`: an attempt after one that failed on a link that stayed up, at most every
   * RETRY_MS, its error told only when it differs from the last one's.
   */
  open(retry = false): void {
    if (this.sub || this.opening || this.closed || this.link === 'refused' || this.client.state !== 'connected') return;
    if (retry && Date.now() < this.notBefore) return;
    this.opening = true;
    const { mode, diagnostics, languages } = this.options;
    this.port
      .subscribe(
        this.client,
        { ...(mode ? { mode } : {}), ...(diagnostics ? { diagnostics } : {}), ...(languages ? { languages } : {}) },
        (e) => this.take(e),
      )
      .then(async (sub) => {
        if (this.closed) return void (await sub.close().catch(() => undefined));
        this.sub = sub;
        this.link = 'up';
        this.lastError = undefined;
        sub.on('active', () => {
          this.link = 'up';
          this.changed();
        });
        sub.on('lost', () => {
          this.link = 'down';
          this.changed();
        });
        sub.on('error', (err: PlcError) => this.onError(this.named(err)));
      })
      .catch((err: unknown) => {
        const e = toPlcError(err);
        if (refusedForGood(e)) this.link = 'refused';
        this.notBefore = Date.now() + RETRY_MS;
        if (e.message === this.lastError) return;
        this.lastError = e.message;
        this.onError(this.named(e));
      })
      .finally(() => {
        this.opening = false;
        this.tried = true;
        this.changed();
      });
  }

  private named(err: PlcError): PlcError {
    if (err.message.startsWith(`device ${this.device}`)) return err;
    return new PlcError(err.code, `device ${this.device}: alarms: ${err.message}`, { cause: err, ...(err.tag ? { tag: err.tag } : {}) });
  }

  private take(e: AlarmEvent): void {
    if (e.type === 'mode' && !this.options.mode) return;
    if (e.type === 'diagnostic' && !this.options.diagnostics) return;
    const at = e.at instanceof Date && !Number.isNaN(e.at.getTime()) ? e.at.getTime() : Date.now();
    this.pending.push({ value: JSON.stringify(plainEvent(e), bigintAsNumber), timestamp: at, late: !this.born });
    this.changed();
  }

  /**
   * Tells the edge node once per turn of the event loop: the events of one burst (one frame of the CPU's, or
   * several read at once) go in one DDATA with the table as they left it, not one DDATA and table each.
   */
  private changed(): void {
    if (this.pendingReport || this.closed) return;
    this.pendingReport = setImmediate(() => {
      this.pendingReport = undefined;
      this.onChange();
    });
  }

  /** Acknowledges alarm `id` at the PLC (its client checks the connection's guard first). */
  acknowledge(id: number): Promise<void> {
    return this.port.acknowledge(this.client, id);
  }

  /** The birth's alarm metrics: every one by name and alias. The events not yet sent stay for the next changes(). */
  birth(now = Date.now()): SparkplugMetric[] {
    this.born = true;
    const [active, count, unacked, event, ack] = this.metrics as [AlarmMetric, AlarmMetric, AlarmMetric, AlarmMetric, AlarmMetric];
    const state = this.state(now);
    this.reported = state.key;
    const last = this.lastEvent;
    return [
      { ...state.table, name: active.name },
      { ...state.active, name: count.name },
      { ...state.unacknowledged, name: unacked.name },
      last
        ? { name: event.name, alias: event.alias, timestamp: last.timestamp, datatype: DataType.String, value: last.value }
        : { name: event.name, alias: event.alias, timestamp: now, datatype: DataType.String, isNull: true, value: null },
      { name: ack.name, alias: ack.alias, timestamp: now, datatype: DataType.UInt32, value: 0 },
    ];
  }

  /** What changed since the last report: every event in order, then the table and counts when they changed. */
  changes(now = Date.now()): SparkplugMetric[] {
    const event = this.metrics[3]!;
    const out: SparkplugMetric[] = this.pending.splice(0).map((p) => {
      this.lastEvent = p;
      return {
        alias: event.alias,
        timestamp: p.timestamp,
        datatype: DataType.String,
        value: p.value,
        ...(p.late ? { isHistorical: true } : {}),
      };
    });
    const state = this.state(now);
    if (state.key !== this.reported) {
      this.reported = state.key;
      out.push(state.table, state.active, state.unacknowledged);
    }
    return out;
  }

  /** The device died (DDEATH): events from now on are sent as historical after its next birth. */
  died(): void {
    this.born = false;
  }

  private state(now: number): { key: string; table: SparkplugMetric; active: SparkplugMetric; unacknowledged: SparkplugMetric } {
    const [active, count, unacked] = this.metrics as [AlarmMetric, AlarmMetric, AlarmMetric];
    if (this.link !== 'up' || !this.sub) {
      const bad = (m: AlarmMetric): SparkplugMetric => ({
        alias: m.alias,
        timestamp: now,
        datatype: m.datatype,
        isNull: true,
        value: null,
        properties: { Quality: { type: DataType.Int32, value: Quality.BAD } },
      });
      return { key: 'bad', table: bad(active), active: bad(count), unacknowledged: bad(unacked) };
    }
    const alarms = this.sub.active;
    const table = tableOf(alarms, this.options.languages?.[0]);
    const counts = alarmCounts(alarms);
    return {
      key: JSON.stringify(table.rows, bigintAsNumber),
      table: { alias: active.alias, timestamp: now, datatype: DataType.DataSet, value: table },
      active: { alias: count.alias, timestamp: now, datatype: DataType.Int32, value: counts.active },
      unacknowledged: { alias: unacked.alias, timestamp: now, datatype: DataType.Int32, value: counts.unacknowledged },
    };
  }

  async close(): Promise<void> {
    this.closed = true;
    if (this.pendingReport) clearImmediate(this.pendingReport);
    const sub = this.sub;
    this.sub = undefined;
    await sub?.close().catch(() => undefined);
  }
}

/** The active alarms as the `Alarms/Active` DataSet (columns ALARM_COLUMNS). */
function tableOf(alarms: readonly PlcAlarm[], language?: string): DataSet {
  return {
    kind: 'DataSet',
    columns: ALARM_COLUMNS.map(([c]) => c),
    types: ALARM_COLUMNS.map(([, t]) => t),
    rows: alarms.map((a) => [
      a.id,
      a.kind,
      a.signal ?? 0,
      a.state,
      a.acknowledged,
      // Classic CPUs send no priority: 0, as a Program_Alarm's lowest.
      a.priority ?? 0,
      // The time of its latest change: when it went, else when it came.
      (a.state === 'going' ? a.going : undefined) ?? a.coming ?? new Date(0),
      alarmText(a, language) ?? '',
    ]),
  };
}

/** JSON has no bigint: an associated LINT/ULINT value as a number where it is exact, else as its digits. */
function bigintAsNumber(_key: string, value: unknown): unknown {
  if (typeof value !== 'bigint') return value;
  return value >= BigInt(Number.MIN_SAFE_INTEGER) && value <= BigInt(Number.MAX_SAFE_INTEGER) ? Number(value) : value.toString();
}
