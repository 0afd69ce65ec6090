/**
 * The PDUs a CPU pushes unasked (alarm and diagnostic indications, mode
 * changes, cyclic data: S7Session.onPush) for the services of an S7 client,
 * on every session it opens, the ones after a reconnect too. A service
 * registers again with the CPU after a reconnect (the CPU forgets a closed
 * connection's registrations); its listener stays here.
 */
import type { S7Session } from './session';

export class PushHub {
  private readonly listeners = new Set<(frame: Buffer) => void>();

  /** Listens to every pushed PDU; returns the function that stops listening. */
  listen(listener: (frame: Buffer) => void): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  /** Routes a new session's pushes here (the client calls this for each session it opens). */
  wire(session: S7Session): S7Session {
    session.onPush((frame) => {
      for (const listener of this.listeners) listener(frame);
    });
    return session;
  }
}
