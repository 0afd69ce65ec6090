/** Sparkplug B 3.0: the payload codec, topics, PLC types as datatypes, and the edge node (docs/sparkplug.md). */
export { DataType, dataTypeName, isDataType, type DataTypeId, type DataTypeName as SparkplugDataTypeName } from './datatypes';
export { encodePayload, decodePayload } from './payload';
export {
  Quality,
  type SparkplugPayload,
  type SparkplugMetric,
  type MetricValue,
  type PropertySet,
  type PropertyValue,
  type MetaData,
  type DataSet,
  type Template,
  type TemplateParameter,
} from './model';
export { NAMESPACE, topicOf, stateTopic, parseTopic, type MessageType, type ParsedTopic } from './topics';
export { parseHostState, type HostState } from './host-state';
export { PLC_DATATYPES, datatypeOfPlcType, datatypeOfAddress, datatypeOfEntry, flattenSymbol, qualityOf } from './types';
export { REBIRTH_METRIC, BDSEQ_METRIC } from './messages';
export type { SparkplugDeviceOptions, MetricDefinition } from './device';
export { ALARM_METRICS, ALARM_COLUMNS, type SparkplugAlarmOptions } from './alarms';
export type { BufferOptions } from './store';
export { SparkplugEdgeNode } from './edge-node';
export type { SparkplugEdgeNodeOptions, EdgeNodeEvents, EdgeNodeState, EdgeNodeStatus, PublishedMessage, CommandDone } from './options';
