/**
 * The Sparkplug B payload as JS values (Sparkplug 3.0, chapter 6 "Payloads"):
 * what encodePayload takes and decodePayload gives. Names are the
 * specification's in camelCase; values are typed by each metric's datatype
 * (lib/sparkplug/scalars.ts, arrays.ts).
 */
import type { ArrayValue } from './arrays';
import type { ScalarValue } from './scalars';

/** A Payload (section 6.4.2). */
export interface SparkplugPayload {
  /** Milliseconds since the epoch, UTC, when the message was made. */
  timestamp?: number;
  metrics: SparkplugMetric[];
  /** 0–255 on an edge node's NBIRTH/NDATA/DBIRTH/DDATA/DDEATH; absent on NDEATH and commands. */
  seq?: number;
  uuid?: string;
  body?: Uint8Array;
}

/** A Metric (section 6.4.3): by name (births, commands) or by alias (data after a birth that defined it). */
export interface SparkplugMetric {
  name?: string;
  /** A number a birth assigns to the name, unique across the edge node (a bigint only beyond 2^53). */
  alias?: number | bigint;
  /** Milliseconds since the epoch, UTC, when the value was taken. */
  timestamp?: number;
  /** A DataType number (lib/sparkplug/datatypes.ts). */
  datatype?: number;
  isHistorical?: boolean;
  isTransient?: boolean;
  /** True: no value (`value` is null). */
  isNull?: boolean;
  metadata?: MetaData;
  properties?: PropertySet;
  /** The value, typed by `datatype`; null with isNull. */
  value?: MetricValue | null;
}

/**
 * A metric's value by datatype: Int8–Int32, UInt8–UInt32, Float, Double: number;
 * Int64, UInt64: bigint (a number is accepted when encoding); Boolean: boolean;
 * String, Text, UUID: string; DateTime: Date; Bytes, File: Uint8Array;
 * arrays: arrays of the element's JS type; DataSet; Template.
 */
export type MetricValue = ScalarValue | Uint8Array | ArrayValue | DataSet | Template;

/** A property's value: a scalar by its `type`, or PropertySet (20), PropertySetList (21). */
export interface PropertyValue {
  type: number;
  value: ScalarValue | PropertySet | PropertySet[] | null;
}

/** A PropertySet (section 6.4.9): properties by key, in the payload's order. */
export type PropertySet = Record<string, PropertyValue>;

/** MetaData (section 6.4.4). */
export interface MetaData {
  isMultiPart?: boolean;
  contentType?: string;
  size?: number;
  seq?: number;
  fileName?: string;
  fileType?: string;
  md5?: string;
  description?: string;
}

/** A DataSet (section 6.4.13): columns with their datatypes, rows of cells (null: no value). */
export interface DataSet {
  readonly kind: 'DataSet';
  columns: string[];
  types: number[];
  rows: (ScalarValue | null)[][];
}

/** A Template (section 6.4.14): a definition (in an NBIRTH) or an instance of one (templateRef). */
export interface Template {
  readonly kind: 'Template';
  version?: string;
  templateRef?: string;
  isDefinition?: boolean;
  metrics: SparkplugMetric[];
  parameters?: TemplateParameter[];
}

/** A Template parameter (section 6.4.15). */
export interface TemplateParameter {
  name: string;
  type: number;
  value: ScalarValue | null;
}

/** The Quality property's codes (section 6.4.10 "Quality Codes"). */
export const Quality = Object.freeze({ BAD: 0, GOOD: 192, STALE: 500 });
