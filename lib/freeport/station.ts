/**
 * One simulated S7-200 freeport station: a data area and the station program
 * of docs/protocols.md (answer frames for its own address, store the first
 * LE bytes of a write, reply with the data it now holds).
 */
import type { FreeportReply, FreeportRequest } from './codec';

export class FreeportStation {
  /** The station's data area; tests and the demo write it directly. */
  readonly data: Buffer;
  /** Silence injection: the station hears but never answers (a powered-off or misaddressed PLC). */
  silent = false;
  /** Fault: answers writes without storing them (the master must report the write as not taken). */
  ignoreWrites = false;
  /** Fault: replies carry this address instead of its own (seen only with a profile whose replies echo DA). */
  answerAs: number | undefined;
  /** Requests this station answered. */
  answered = 0;

  constructor(
    readonly address: number,
    dataBytes = 4,
    initial?: Buffer,
  ) {
    this.data = Buffer.alloc(dataBytes);
    initial?.copy(this.data, 0, 0, Math.min(initial.length, dataBytes));
  }

  /** The reply to a request addressed to this station, or undefined when it stays silent. */
  handle(request: FreeportRequest, echoAddress: boolean): FreeportReply | undefined {
    if (request.station !== this.address || this.silent) return undefined;
    if (request.command === 'write' && !this.ignoreWrites) request.data.copy(this.data, 0, 0, request.length);
    this.answered++;
    const data = Buffer.from(this.data);
    return echoAddress ? { station: this.answerAs ?? this.address, data } : { data };
  }
}
