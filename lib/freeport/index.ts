/** S7-200 freeport: profile, codec, parser, addresses, master and bus simulator. */
export * from './profile';
export * from './codec';
export * from './parser';
export * from './address';
export { FreeportSession, type FreeportTransport, type BusDiscipline, type Exchange } from './session';
export { FreeportClient, type FreeportClientOptions } from './client';
export { FreeportStation } from './station';
export { FreeportBus, type FreeportBusOptions, type FreeportBusFaults, type SerialAttachOptions } from './bus';
