/**
 * Encodes and decodes Sparkplug B payloads (Sparkplug 3.0, chapter 6) with
 * the schema of lib/sparkplug/schema.ts. Pure: values to bytes and back.
 * Encoding checks every value against its metric's datatype (INVALID_VALUE
 * naming the metric); decoding a malformed or inconsistent payload throws a
 * PROTOCOL_ERROR naming the metric, never an untyped error.
 */
import { PlcError, ValueError } from '../errors';
import { packArray, unpackArray } from './arrays';
import { ARRAY_ELEMENT, DataType, dataTypeName, isDataType } from './datatypes';
import { fromUint64, toUint64Bits } from './integers';
import type { DataSet, MetaData, MetricValue, SparkplugMetric, SparkplugPayload, Template } from './model';
import { decodePropertySet, encodePropertySet } from './properties';
import { isScalarType, scalarFields, scalarValue, type ScalarFields } from './scalars';
import { PAYLOAD_TYPE } from './schema';

type Message = Record<string, unknown>;

/** The bytes of a payload. */
export function encodePayload(payload: SparkplugPayload): Buffer {
  const message: Message = { metrics: payload.metrics.map((m, i) => encodeMetric(m, metricLabel(m, i))) };
  if (payload.timestamp !== undefined) message['timestamp'] = toUint64Bits(payload.timestamp);
  if (payload.seq !== undefined) message['seq'] = toUint64Bits(payload.seq);
  if (payload.uuid !== undefined) message['uuid'] = payload.uuid;
  if (payload.body !== undefined) message['body'] = payload.body;
  return Buffer.from(PAYLOAD_TYPE.encode(PAYLOAD_TYPE.fromObject(message)).finish());
}

/** A payload from its bytes. */
export function decodePayload(bytes: Uint8Array): SparkplugPayload {
  let message: Message;
  try {
    message = PAYLOAD_TYPE.decode(bytes) as unknown as Message;
  } catch (err) {
    throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: not a protobuf Payload (${(err as Error).message})`, { cause: err });
  }
  const payload: SparkplugPayload = { metrics: ((message['metrics'] as Message[]) ?? []).map((m, i) => decodeMetric(m, `#${i}`)) };
  if (has(message, 'timestamp')) payload.timestamp = Number(fromUint64(message['timestamp']));
  if (has(message, 'seq')) payload.seq = Number(fromUint64(message['seq']));
  if (has(message, 'uuid')) payload.uuid = message['uuid'] as string;
  if (has(message, 'body')) payload.body = message['body'] as Uint8Array;
  return payload;
}

function metricLabel(m: SparkplugMetric, index: number): string {
  return m.name ?? (m.alias !== undefined ? `alias ${m.alias}` : `#${index}`);
}

function has(message: Message, field: string): boolean {
  return Object.prototype.hasOwnProperty.call(message, field) && message[field] !== null && message[field] !== undefined;
}

function encodeMetric(m: SparkplugMetric, what: string): Message {
  const out: Message = {};
  if (m.name !== undefined) out['name'] = m.name;
  if (m.alias !== undefined) out['alias'] = toUint64Bits(m.alias);
  if (m.timestamp !== undefined) out['timestamp'] = toUint64Bits(m.timestamp);
  if (m.datatype !== undefined) {
    if (!isDataType(m.datatype)) throw new ValueError(what, `${m.datatype} is not a Sparkplug datatype`);
    out['datatype'] = m.datatype;
  }
  if (m.isHistorical) out['is_historical'] = true;
  if (m.isTransient) out['is_transient'] = true;
  if (m.metadata) out['metadata'] = encodeMetaData(m.metadata);
  if (m.properties) out['properties'] = encodePropertySet(m.properties, what);
  if (m.isNull || m.value === null) out['is_null'] = true;
  else if (m.value !== undefined) {
    if (m.datatype === undefined) throw new ValueError(what, 'a value needs its datatype');
    Object.assign(out, encodeValue(m.datatype, m.value, what));
  }
  return out;
}

function encodeValue(type: number, value: MetricValue, what: string): Message {
  if (isScalarType(type)) return scalarFields(type, value, what) as Message;
  if (ARRAY_ELEMENT[type] !== undefined) return { bytes_value: packArray(type, value, what) };
  switch (type) {
    case DataType.Bytes:
    case DataType.File:
      if (!(value instanceof Uint8Array)) throw new ValueError(what, `a ${dataTypeName(type)} takes a Uint8Array (Buffer)`);
      return { bytes_value: value };
    case DataType.DataSet:
      return { dataset_value: encodeDataSet(value as DataSet, what) };
    case DataType.Template:
      return { template_value: encodeTemplate(value as Template, what) };
    default:
      throw new ValueError(what, `a metric cannot hold a ${dataTypeName(type)}`);
  }
}

function decodeMetric(m: Message, index: string): SparkplugMetric {
  const out: SparkplugMetric = {};
  if (has(m, 'name')) out.name = m['name'] as string;
  if (has(m, 'alias')) {
    const alias = fromUint64(m['alias']);
    out.alias = alias <= BigInt(Number.MAX_SAFE_INTEGER) ? Number(alias) : alias;
  }
  const what = out.name ?? (out.alias !== undefined ? `alias ${out.alias}` : index);
  if (has(m, 'timestamp')) out.timestamp = Number(fromUint64(m['timestamp']));
  if (has(m, 'datatype')) out.datatype = m['datatype'] as number;
  if (has(m, 'is_historical')) out.isHistorical = m['is_historical'] as boolean;
  if (has(m, 'is_transient')) out.isTransient = m['is_transient'] as boolean;
  if (has(m, 'metadata')) out.metadata = decodeMetaData(m['metadata'] as Message);
  if (has(m, 'properties')) out.properties = decodePropertySet(m['properties'] as Message, what);
  if (m['is_null'] === true) {
    out.isNull = true;
    out.value = null;
  } else {
    const value = decodeValue(out.datatype, m, what);
    if (value !== undefined) out.value = value;
  }
  return out;
}

/** The metric's value; undefined when it carries none (a data message by alias, without its datatype, holds the value's field only). */
function decodeValue(type: number | undefined, m: Message, what: string): MetricValue | undefined {
  if (type === undefined) return undefined;
  if (!isDataType(type)) throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: metric ${what}: unknown datatype ${type}`, { tag: what });
  if (isScalarType(type)) return type === DataType.Unknown ? undefined : scalarValue(type, m as ScalarFields, `metric ${what}`);
  if (ARRAY_ELEMENT[type] !== undefined) {
    if (!has(m, 'bytes_value'))
      throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: metric ${what}: a ${dataTypeName(type)} without its bytes_value`, {
        tag: what,
      });
    return unpackArray(type, m['bytes_value'] as Uint8Array, what);
  }
  switch (type) {
    case DataType.Bytes:
    case DataType.File:
      return has(m, 'bytes_value') ? Buffer.from(m['bytes_value'] as Uint8Array) : Buffer.alloc(0);
    case DataType.DataSet:
      return has(m, 'dataset_value') ? decodeDataSet(m['dataset_value'] as Message, what) : undefined;
    case DataType.Template:
      return has(m, 'template_value') ? decodeTemplate(m['template_value'] as Message, what) : undefined;
    default:
      throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: metric ${what}: a metric cannot hold a ${dataTypeName(type)}`, {
        tag: what,
      });
  }
}

const META_FIELDS: readonly [keyof MetaData, string][] = [
  ['isMultiPart', 'is_multi_part'],
  ['contentType', 'content_type'],
  ['size', 'size'],
  ['seq', 'seq'],
  ['fileName', 'file_name'],
  ['fileType', 'file_type'],
  ['md5', 'md5'],
  ['description', 'description'],
];

function encodeMetaData(meta: MetaData): Message {
  const out: Message = {};
  for (const [key, field] of META_FIELDS) {
    const v = meta[key];
    if (v !== undefined) out[field] = key === 'size' || key === 'seq' ? toUint64Bits(v as number) : v;
  }
  return out;
}

function decodeMetaData(m: Message): MetaData {
  const out: Record<string, unknown> = {};
  for (const [key, field] of META_FIELDS) {
    if (has(m, field)) out[key] = key === 'size' || key === 'seq' ? Number(fromUint64(m[field])) : m[field];
  }
  return out as MetaData;
}

function encodeDataSet(ds: DataSet, what: string): Message {
  if (ds.columns.length !== ds.types.length) {
    throw new ValueError(what, `a DataSet of ${ds.columns.length} columns needs as many types, got ${ds.types.length}`);
  }
  const rows = ds.rows.map((row, r) => {
    if (row.length !== ds.columns.length)
      throw new ValueError(`${what}[${r}]`, `a row of ${row.length} cells in a DataSet of ${ds.columns.length} columns`);
    return { elements: row.map((cell, c) => (cell === null ? {} : scalarFields(ds.types[c]!, cell, `${what}[${r}].${ds.columns[c]}`))) };
  });
  return { num_of_columns: toUint64Bits(ds.columns.length), columns: ds.columns, types: ds.types, rows };
}

function decodeDataSet(m: Message, what: string): DataSet {
  const columns = (m['columns'] as string[]) ?? [];
  const types = (m['types'] as number[]) ?? [];
  if (columns.length !== types.length) {
    throw new PlcError(
      'PROTOCOL_ERROR',
      `Sparkplug payload: metric ${what}: a DataSet of ${columns.length} columns with ${types.length} types`,
      { tag: what },
    );
  }
  const rows = ((m['rows'] as Message[]) ?? []).map((row, r) =>
    ((row['elements'] as Message[]) ?? []).map((cell, c) => {
      const type = types[c];
      if (type === undefined)
        throw new PlcError('PROTOCOL_ERROR', `Sparkplug payload: metric ${what}: row ${r} has more cells than columns`, { tag: what });
      return Object.keys(cell).length === 0 ? null : scalarValue(type, cell as ScalarFields, `metric ${what}[${r}].${columns[c]}`);
    }),
  );
  return { kind: 'DataSet', columns: [...columns], types: [...types], rows };
}

function encodeTemplate(t: Template, what: string): Message {
  const out: Message = { metrics: t.metrics.map((m, i) => encodeMetric(m, `${what}/${metricLabel(m, i)}`)) };
  if (t.version !== undefined) out['version'] = t.version;
  if (t.templateRef !== undefined) out['template_ref'] = t.templateRef;
  if (t.isDefinition !== undefined) out['is_definition'] = t.isDefinition;
  if (t.parameters) {
    out['parameters'] = t.parameters.map((p) => ({
      name: p.name,
      type: p.type,
      ...(p.value === null ? {} : scalarFields(p.type, p.value, `${what} parameter ${p.name}`)),
    }));
  }
  return out;
}

function decodeTemplate(m: Message, what: string): Template {
  const out: Template = { kind: 'Template', metrics: ((m['metrics'] as Message[]) ?? []).map((x, i) => decodeMetric(x, `${what}/#${i}`)) };
  if (has(m, 'version')) out.version = m['version'] as string;
  if (has(m, 'template_ref')) out.templateRef = m['template_ref'] as string;
  if (has(m, 'is_definition')) out.isDefinition = m['is_definition'] as boolean;
  const params = (m['parameters'] as Message[]) ?? [];
  if (params.length > 0) {
    out.parameters = params.map((p) => {
      const name = (p['name'] as string) ?? '';
      const type = (p['type'] as number) ?? DataType.Unknown;
      const set = ['int_value', 'long_value', 'float_value', 'double_value', 'boolean_value', 'string_value'].some((f) => has(p, f));
      return { name, type, value: set ? scalarValue(type, p as ScalarFields, `metric ${what} parameter ${name}`) : null };
    });
  }
  return out;
}
