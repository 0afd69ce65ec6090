export * from './backoff';
export * from './framer';
export * from './jobs';
export * from './pending';
export * from './serial';
export * from './supervisor';
export * from './tcp';
