/**
 * Fuzz targets of the Sparkplug B codec (lib/sparkplug/payload.ts) and the primary host's STATE
 * (lib/sparkplug/host-state.ts): what any client of the broker can publish on a DCMD, NCMD or STATE topic
 * the edge node subscribes (issue #34).
 */
import { DataType } from '../../lib/sparkplug/datatypes';
import { parseHostState } from '../../lib/sparkplug/host-state';
import { nbirthPayload, ndeathPayload } from '../../lib/sparkplug/messages';
import type { SparkplugPayload } from '../../lib/sparkplug/model';
import { decodePayload, encodePayload } from '../../lib/sparkplug/payload';
import type { FuzzTarget } from './engine';

const NOW = Date.UTC(2026, 11, 3, 12);

/** Payloads of every kind of value: births, data by alias, a DCMD, the alarm table, a Template, properties, arrays. */
function payloadSeeds(): Buffer[] {
  const payloads: SparkplugPayload[] = [
    nbirthPayload(7, NOW),
    ndeathPayload(7, NOW),
    {
      timestamp: NOW,
      seq: 1,
      metrics: [
        { name: 'Level', alias: 0, timestamp: NOW, datatype: DataType.Int16, value: -300 },
        { name: 'Count', alias: 1, timestamp: NOW, datatype: DataType.UInt64, value: 18446744073709551615n },
        { name: 'Speed', alias: 2, timestamp: NOW, datatype: DataType.Float, value: 1.5 },
        { name: 'Run', alias: 3, timestamp: NOW, datatype: DataType.Boolean, value: true },
        { name: 'Name', alias: 4, timestamp: NOW, datatype: DataType.String, value: 'Tank' },
        { name: 'When', alias: 5, timestamp: NOW, datatype: DataType.DateTime, value: new Date(NOW) },
        { name: 'Levels', alias: 6, timestamp: NOW, datatype: DataType.Int32Array, value: [-1, 2, 3] },
        { name: 'Flags', alias: 7, timestamp: NOW, datatype: DataType.BooleanArray, value: [true, false, true] },
        { name: 'Names', alias: 8, timestamp: NOW, datatype: DataType.StringArray, value: ['a', 'bc'] },
        {
          name: 'Bad',
          alias: 9,
          timestamp: NOW,
          datatype: DataType.Double,
          isNull: true,
          value: null,
          properties: { Quality: { type: DataType.Int32, value: 0 } },
        },
      ],
    },
    { timestamp: NOW, seq: 2, metrics: [{ alias: 0, timestamp: NOW, datatype: DataType.Int16, value: 7, isHistorical: true }] },
    { timestamp: NOW, metrics: [{ name: 'Alarms/Acknowledge', datatype: DataType.UInt32, value: 257 }] },
    {
      timestamp: NOW,
      seq: 3,
      metrics: [
        {
          name: 'Alarms/Active',
          alias: 10,
          timestamp: NOW,
          datatype: DataType.DataSet,
          value: {
            kind: 'DataSet',
            columns: ['Id', 'Kind', 'Acknowledged', 'Time'],
            types: [DataType.UInt32, DataType.String, DataType.Boolean, DataType.DateTime],
            rows: [[257, 'ALARM_SQ', false, new Date(NOW)]],
          },
        },
      ],
    },
    {
      timestamp: NOW,
      metrics: [
        {
          name: 'Motor',
          datatype: DataType.Template,
          value: {
            kind: 'Template',
            templateRef: 'MotorType',
            version: '1',
            metrics: [{ name: 'Speed', datatype: DataType.Float, value: 1 }],
            parameters: [{ name: 'p', type: DataType.String, value: 'v' }],
          },
        },
      ],
    },
  ];
  return [
    ...payloads.map((p) => encodePayload(p)),
    // A UInt32 in long_value, as Eclipse Tahu 1.0.21 sends one.
    Buffer.from('12080a01782007588102', 'hex'),
  ];
}

export function sparkplugTargets(): FuzzTarget[] {
  return [
    { name: 'Sparkplug payload (DCMD, NCMD)', seeds: payloadSeeds(), run: (b) => void decodePayload(b) },
    {
      name: 'Sparkplug STATE of the primary host',
      seeds: [
        Buffer.from(JSON.stringify({ online: true, timestamp: NOW })),
        Buffer.from(JSON.stringify({ online: false, timestamp: NOW })),
        Buffer.from('OFFLINE'),
      ],
      run: (b) => void parseHostState(b),
    },
  ];
}
