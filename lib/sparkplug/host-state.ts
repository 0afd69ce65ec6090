/**
 * The primary host application's STATE (Sparkplug 3.0, section 5.4 "Primary
 * Host Application STATE flows" and 6.1.2 "STATE payload"): a retained JSON
 * `{"online": boolean, "timestamp": ms}` on `spBv1.0/STATE/<host_id>`. A
 * message older than the last one taken (smaller timestamp) is stale and
 * ignored (tck-id-message-flow-edge-node-birth-publish-phid-wait-timestamp,
 * tck-id-operational-behavior-edge-node-termination-host-offline-timestamp).
 */
export interface HostState {
  online: boolean;
  timestamp: number;
}

/** The STATE payload, or undefined when it is not the specification's JSON. */
export function parseHostState(payload: Uint8Array): HostState | undefined {
  let value: unknown;
  try {
    value = JSON.parse(Buffer.from(payload).toString('utf8'));
  } catch {
    return undefined;
  }
  if (typeof value !== 'object' || value === null) return undefined;
  const { online, timestamp } = value as Record<string, unknown>;
  if (typeof online !== 'boolean' || typeof timestamp !== 'number' || !Number.isFinite(timestamp)) return undefined;
  return { online, timestamp };
}

/** What one STATE message means to an edge node that waits for its primary host. */
export type HostTransition = 'online' | 'offline' | 'stale';

/** Tracks the primary host's STATE across messages (and brokers: the timestamps stay comparable). */
export class HostStateTracker {
  private last: HostState | undefined;

  get online(): boolean {
    return this.last?.online === true;
  }

  /** Takes a STATE message; 'stale' when its timestamp is older than the last one taken (it is then ignored). */
  take(state: HostState): HostTransition {
    const last = this.last;
    if (last && state.timestamp < last.timestamp) return 'stale';
    this.last = state;
    return state.online ? 'online' : 'offline';
  }

  /** Forgets whether the host is online (a new broker session waits for its STATE again), keeping the last timestamp. */
  unknown(): void {
    if (this.last) this.last = { online: false, timestamp: this.last.timestamp };
  }
}
