export { S7PlusClient, type InsecureEvent, type S7PlusClientEvents } from './client';
export { S7PlusSubscription } from './subscription';
export type { SubscribeOptions, SubscriptionChange, SubscriptionData, SubscriptionState } from './subscription';
