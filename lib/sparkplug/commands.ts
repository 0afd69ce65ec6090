/**
 * A host's DCMD metrics checked against the device's configuration before
 * anything reaches the PLC (Sparkplug 3.0, section 5.9 "Device Command"):
 * the metric must be one of the device's, made writable by the edge node's
 * options, and its value of the metric's datatype and range. What passes is
 * written through the client, whose read-only and allow-list guard still
 * decides (lib/client/options.ts).
 */
import { PlcError, toPlcError, ValueError, type TagResult } from '../errors';
import { ARRAY_ELEMENT, dataTypeName } from './datatypes';
import type { SparkplugDevice } from './device';
import { REBIRTH_METRIC } from './messages';
import type { SparkplugMetric, SparkplugPayload } from './model';
import { packArray } from './arrays';
import { isScalarType, scalarFields } from './scalars';

/** A checked write: the metric, its tag and the value to write. */
export interface CommandWrite {
  metric: string;
  address: string;
  value: unknown;
  /** `Alarms/Acknowledge`: the value is the id of the alarm to acknowledge, not a tag's value. */
  acknowledge?: true;
}

/** The write a DCMD metric asks for, or the typed error that refuses it. */
function checkCommand(device: SparkplugDevice, m: SparkplugMetric): CommandWrite | PlcError {
  const def = device.metric(m);
  const label = m.name ?? (m.alias !== undefined ? `alias ${m.alias}` : '(unnamed)');
  const what = `${device.name}/${label}`;
  if (!def) return new PlcError('INVALID_ADDRESS', `DCMD for device ${device.name}: no metric ${label}`, { tag: what });
  if (!def.writable) {
    return new PlcError(
      'WRITE_NOT_ALLOWED',
      `DCMD for device ${device.name}: metric "${def.name}" is not writable (the edge node's writable list does not name it)`,
      {
        tag: what,
      },
    );
  }
  if (def.datatype === undefined)
    return new PlcError('NOT_CONNECTED', `DCMD for device ${device.name}: metric "${def.name}" has no datatype yet (never read)`, {
      tag: what,
    });
  if (m.isNull || m.value === null || m.value === undefined) return new ValueError(what, 'a DCMD needs a value');
  if (m.datatype !== undefined && m.datatype !== def.datatype) {
    return new ValueError(what, `the metric is a ${dataTypeName(def.datatype)}, the DCMD sent a ${dataTypeName(m.datatype)}`);
  }
  try {
    if (isScalarType(def.datatype)) scalarFields(def.datatype, m.value, what);
    else if (ARRAY_ELEMENT[def.datatype] !== undefined) packArray(def.datatype, m.value, what);
    else return new ValueError(what, `a ${dataTypeName(def.datatype)} metric cannot be written`);
  } catch (err) {
    return err as PlcError;
  }
  return { metric: def.name, address: def.address, value: m.value, ...(def.acknowledge ? { acknowledge: true as const } : {}) };
}

/** Checks a DCMD's metrics and writes those that pass in one request: what was written, and every refusal or failure. */
export async function executeCommand(
  device: SparkplugDevice,
  payload: SparkplugPayload,
): Promise<{ done: CommandWrite[]; errors: PlcError[] }> {
  const errors: PlcError[] = [];
  const writes: CommandWrite[] = [];
  const acks: CommandWrite[] = [];
  for (const m of payload.metrics) {
    const checked = checkCommand(device, m);
    if (checked instanceof PlcError) errors.push(checked);
    else (checked.acknowledge ? acks : writes).push(checked);
  }
  const acked = await acknowledge(device, acks, errors);
  if (writes.length === 0) return { done: acked, errors };
  let results: Record<string, TagResult<void>>;
  try {
    results = await device.client.writeDetailed(Object.fromEntries(writes.map((w) => [w.address, w.value])));
  } catch (err) {
    return { done: acked, errors: [...errors, toPlcError(err, 'PLC_ERROR')] };
  }
  const done: CommandWrite[] = [...acked];
  for (const w of writes) {
    const r = results[w.address];
    if (r && !r.ok) errors.push(r.error);
    else done.push(w);
  }
  return { done, errors };
}

/** Acknowledges each alarm a DCMD names, in order, through the device's alarms port (whose client applies the ack guard). */
async function acknowledge(device: SparkplugDevice, acks: readonly CommandWrite[], errors: PlcError[]): Promise<CommandWrite[]> {
  const done: CommandWrite[] = [];
  for (const a of acks) {
    try {
      await device.alarms!.acknowledge(Number(a.value));
      done.push(a);
    } catch (err) {
      const e = toPlcError(err, 'PLC_ERROR');
      errors.push(
        new PlcError(e.code, `DCMD for device ${device.name}: ${a.metric} ${String(a.value)}: ${e.message}`, {
          cause: e,
          tag: e.tag ?? `${device.name}/${a.metric}`,
        }),
      );
    }
  }
  return done;
}

/** An NCMD: whether it asks for a rebirth (`Node Control/Rebirth` true, section 5.6), and every metric it sends that this edge node does not take. */
export function checkNodeCommand(payload: SparkplugPayload): { rebirth: boolean; errors: PlcError[] } {
  let rebirth = false;
  const errors: PlcError[] = [];
  for (const m of payload.metrics) {
    if (m.name === REBIRTH_METRIC && m.value === true) rebirth = true;
    else
      errors.push(
        new PlcError(
          'NOT_SUPPORTED',
          `NCMD metric ${m.name ?? `alias ${m.alias}`} is not one this edge node takes (only ${REBIRTH_METRIC})`,
        ),
      );
  }
  return { rebirth, errors };
}
