/**
 * The s7 driver's alarms port (lib/drivers.ts): the classic alarms of an
 * S7-300/400 (lib/s7/client/alarms.ts) for every caller that reaches
 * alarms through the registry (`plcwire alarms`, `plcwire ack`, the
 * alarms node, the dashboard).
 */
import type { AlarmPort } from '../alarms/model';
import type { S7Client } from './client/client';

const port: AlarmPort<S7Client> = {
  list: (client, options) => client.alarms(options),
  subscribe: (client, options, listener) => client.subscribeAlarms(options, listener),
  acknowledge: (client, id, options) => client.acknowledge(id, options),
};

export const S7_ALARMS: AlarmPort<S7Client> = Object.freeze(port);
