/**
 * @plcwire/node-red-siemens — connect Node.js to Siemens PLCs over S7comm
 * (ISO-on-TCP), FETCH/WRITE and S7-200 freeport, with a simulator for each.
 *
 *   const plc = await connect('s7://192.168.0.2?rack=0&slot=1');
 *   await plc.read(['DB1,INT2', 'DB1.DBD4:REAL', 'M0.1']);
 */
export { connect, createClient, type AnyClient, type ConnectOptions } from './connect';
export * from './errors';
export * from './types';
export * from './url';

export { parseAddress, parseTypeSpec, formatAddress } from './address';
export * as values from './values';
export { decodeTag, encodeTag, encodeInto, validateValue, elementByteLength, tagByteLength } from './values';

export { BaseClient, type ClientOptions, type DriverSession } from './link/client-base';

export * as s7 from './s7/codec';
export { S7Client } from './s7/client';
export { S7Server } from './s7/server';
export * as fetchwrite from './fetchwrite/codec';
export { FetchWriteClient } from './fetchwrite/client';
export { FetchWriteServer } from './fetchwrite/server';
export { FreeportClient } from './freeport/client';
export { FreeportBus } from './freeport/bus';

export { PlcMemory, DEFAULT_LAYOUT, type MemoryLayout, type MemoryAccess } from './sim/memory';
export { DemoProcess, DEMO_TAGS } from './demo/process';
export { startPlant, DEMO_PORTS, DEMO_STATIONS, type Plant } from './demo/plant';
