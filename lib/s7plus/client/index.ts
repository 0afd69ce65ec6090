export { S7PlusClient } from './client';
export { S7PlusSubscription } from './subscription';
export type { SubscribeOptions, SubscriptionChange, SubscriptionData, SubscriptionState } from './subscription';
