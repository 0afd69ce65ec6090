/** The S7 client: `S7Client` (client.ts), its session (session.ts) and the CPU services (services.ts). */
export { S7Client, S7Session, localTsapFor, type ItemLimitEvent, type S7ClientEvents, type S7Stats } from './client';
export { type ClockOptions, type PlcInfo } from './services';
