/**
 * S7Client: S7comm over ISO-on-TCP on the shared link layer. It uses the PDU
 * size and parallel jobs (AmQ) the PLC negotiated, packs tags into the fewest
 * PDUs (planner.ts), keeps up to AmQ jobs in flight, and gives a result per
 * tag: a missing DB or an address out of range fails only its own tags.
 */
import type * as net from 'node:net';
import { parseAddress } from '../address';
import { ConnectionError, PlcError, ProtocolError, TimeoutError, toPlcError, type TagResult } from '../errors';
import { BaseClient, type ClientOptions } from '../link/client-base';
import { FrameReader } from '../link/framer';
import { JobQueue } from '../link/jobs';
import { PendingRequests, abortError } from '../link/pending';
import { openTcp } from '../link/tcp';
import type { PlcValue, Protocol, Tag } from '../types';
import { endpointName, type S7Endpoint } from '../url';
import { decodeTag, validateValue } from '../values';
import {
  checkTpkt,
  decodeCotp,
  decodeS7,
  encodeConnectionRequest,
  encodeReadRequest,
  encodeSetupCommunication,
  encodeWriteRequest,
  type S7Message,
} from './codec';
import { LOCAL_TSAP, describeReturnCode, headerError, remoteTsapFor } from './constants';
import { planRead, planWrite, type ReadPlan } from './planner';

/** Counters for diagnostics and the benchmark. */
export interface S7Stats {
  pdusSent: number;
  bytesSent: number;
  bytesReceived: number;
}

class S7Session {
  readonly pending = new PendingRequests<S7Message>();
  readonly jobs: JobQueue;
  private nextRef = 1;

  constructor(
    readonly socket: net.Socket,
    readonly reader: FrameReader,
    readonly pduSize: number,
    readonly maxJobs: number,
    maxQueued: number | undefined,
  ) {
    this.jobs = new JobQueue({ concurrency: maxJobs, ...(maxQueued === undefined ? {} : { maxQueued }) });
  }

  ref(): number {
    // 1..65535, skipping refs still pending (a late answer must never match a new job).
    do this.nextRef = this.nextRef >= 0xffff ? 1 : this.nextRef + 1;
    while (this.pending.has(this.nextRef));
    return this.nextRef;
  }

  destroy(): void {
    this.socket.destroy();
  }
}

export class S7Client extends BaseClient<S7Session, Tag> {
  readonly protocol: Protocol = 's7';
  readonly endpoint: S7Endpoint;
  readonly stats: S7Stats = { pdusSent: 0, bytesSent: 0, bytesReceived: 0 };
  private readonly plans = new Map<string, ReadPlan>();

  constructor(endpoint: S7Endpoint, options: Partial<ClientOptions> = {}) {
    super({
      name: endpointName(endpoint),
      timeout: endpoint.timeout,
      ...(endpoint.readOnly ? { readOnly: true } : {}),
      ...(endpoint.allow ? { allow: endpoint.allow } : {}),
      ...options,
    });
    this.endpoint = endpoint;
  }

  /** The PDU size the PLC negotiated (0 while disconnected). */
  get pduSize(): number {
    return this.session?.pduSize ?? 0;
  }

  /** The parallel jobs (AmQ) the PLC negotiated (0 while disconnected). */
  get maxJobs(): number {
    return this.session?.maxJobs ?? 0;
  }

  protected parseTag(address: string): Tag {
    return parseAddress(address);
  }

  protected async openSession(signal: AbortSignal): Promise<S7Session> {
    const e = this.endpoint;
    const socket = await openTcp({ host: e.host, port: e.port, timeout: this.timeout, signal });
    try {
      const reader = new FrameReader(checkTpkt, 70_000);
      const next = frameWaiter(socket, reader, signal, this.name);
      const calledTsap = e.remoteTsap ?? remoteTsapFor(e.connectionType, e.rack, e.slot);
      socket.write(encodeConnectionRequest({ sourceRef: 0x0001, callingTsap: e.localTsap ?? LOCAL_TSAP, calledTsap, tpduSize: 0x0a }));
      const cc = decodeCotp(await next());
      if (cc.type !== 'CC') {
        const where = e.remoteTsap !== undefined ? `TSAP ${hex4(calledTsap)}` : `rack ${e.rack}, slot ${e.slot}`;
        throw new ConnectionError('CONNECT_FAILED', `${this.name} refused the connection (${where}): wrong rack/slot or TSAP, or the PLC's connection limit is reached`);
      }
      socket.write(encodeSetupCommunication(0, { maxAmqCalling: 8, maxAmqCalled: 8, pduSize: e.pduSize }));
      const ack = decodeS7(await next());
      if (ack.kind === 'error') throw headerError(ack.errorClass, ack.errorCode, `${this.name} setup communication`);
      if (ack.kind !== 'setup-ack') throw new ProtocolError(`${this.name}: expected the setup communication answer`);
      const { pduSize } = ack.params;
      if (pduSize < 64) throw new ProtocolError(`${this.name} negotiated an unusable PDU size of ${pduSize}`);
      const maxJobs = Math.max(1, Math.min(ack.params.maxAmqCalling, ack.params.maxAmqCalled) || 1);
      next.stop();
      const session = new S7Session(socket, reader, pduSize, maxJobs, this.maxQueued);
      this.attach(session);
      return session;
    } catch (err) {
      socket.destroy();
      throw signal.aborted ? abortError(`connecting to ${this.name}`, signal) : toPlcError(err, 'CONNECT_FAILED');
    }
  }

  private attach(session: S7Session): void {
    const { socket } = session;
    const fail = (cause: PlcError) => {
      const err = this.state === 'closed' ? new ConnectionError('CLOSED', `${this.name}: the client was closed`, { cause }) : cause;
      session.pending.rejectAll(err);
      session.jobs.rejectAll(err);
      socket.destroy();
      this.sessionLost(session, err);
    };
    const onFrames = (frames: Buffer[]) => {
      for (const frame of frames) {
        let message: S7Message;
        try {
          message = decodeS7(frame);
        } catch (err) {
          return fail(toPlcError(err, 'PROTOCOL_ERROR'));
        }
        // An answer nobody waits for (late, after a timeout, or duplicated) is dropped.
        session.pending.resolve(message.pduRef, message);
      }
    };
    socket.on('data', (chunk: Buffer) => {
      this.stats.bytesReceived += chunk.length;
      let frames: Buffer[];
      try {
        frames = session.reader.push(chunk);
      } catch (err) {
        return fail(toPlcError(err, 'PROTOCOL_ERROR'));
      }
      onFrames(frames);
    });
    socket.on('error', (err) => fail(new ConnectionError('CONNECTION_LOST', `${this.name}: ${err.message}`, { cause: err })));
    socket.on('close', () => fail(new ConnectionError('CONNECTION_LOST', `${this.name} closed the connection`)));
  }

  /** Sends one job and waits for its answer; a timeout drops the link (the PLC is not answering). */
  private request(session: S7Session, build: (ref: number) => Buffer, what: string, signal?: AbortSignal): Promise<S7Message> {
    return session.jobs.run(async () => {
      const ref = session.ref();
      const frame = build(ref);
      const answer = session.pending.add(ref, this.timeout, `${this.name} ${what}`, signal);
      this.stats.pdusSent++;
      this.stats.bytesSent += frame.length;
      session.socket.write(frame);
      try {
        return await answer;
      } catch (err) {
        if (err instanceof TimeoutError) {
          session.socket.destroy();
          this.sessionLost(session, new ConnectionError('CONNECTION_LOST', `${this.name} stopped answering (${err.message})`));
        }
        throw err;
      }
    }, signal);
  }

  protected async readTags(session: S7Session, tags: readonly Tag[], signal?: AbortSignal): Promise<TagResult<PlcValue>[]> {
    const plan = this.planFor(tags, session.pduSize);
    const results = await this.execute(session, tags, plan, signal);
    // A merged item that failed may hide good tags (one past the end of a DB fails its neighbours): read those alone.
    const retry = plan.ranges.filter((r, i) => r.tags.length > 1 && !results.rangeOk[i]).flatMap((r) => r.tags);
    if (retry.length > 0) {
      const alone = retry.map((i) => tags[i]!);
      const second = await this.execute(session, alone, planRead(alone, session.pduSize, false), signal);
      retry.forEach((i, k) => (results.values[i] = second.values[k]!));
    }
    return results.values;
  }

  private planFor(tags: readonly Tag[], pduSize: number): ReadPlan {
    let key = `${pduSize}`;
    for (const t of tags) key += `\u0000${t.address}`;
    let plan = this.plans.get(key);
    if (!plan) {
      if (this.plans.size >= 64) this.plans.clear();
      plan = planRead(tags, pduSize);
      this.plans.set(key, plan);
    }
    return plan;
  }

  private async execute(
    session: S7Session,
    tags: readonly Tag[],
    plan: ReadPlan,
    signal?: AbortSignal,
  ): Promise<{ values: TagResult<PlcValue>[]; rangeOk: boolean[] }> {
    const buffers = plan.ranges.map((r) => Buffer.allocUnsafe(r.length));
    const errors: (PlcError | undefined)[] = plan.ranges.map(() => undefined);
    await Promise.all(
      plan.pdus.map(async (chunks) => {
        const answer = await this.request(session, (ref) => encodeReadRequest(ref, chunks.map((c) => c.item)), `read of ${chunks.length} item(s)`, signal);
        if (answer.kind === 'error') {
          const err = headerError(answer.errorClass, answer.errorCode, `${this.name} read`);
          for (const c of chunks) errors[c.range] ??= err;
          return;
        }
        if (answer.kind !== 'read-ack' || answer.items.length !== chunks.length) {
          const err = new ProtocolError(`${this.name}: the answer to a read of ${chunks.length} item(s) does not match it`);
          for (const c of chunks) errors[c.range] ??= err;
          return;
        }
        chunks.forEach((c, i) => {
          const item = answer.items[i]!;
          if (item.returnCode !== 0xff) {
            const { code, text } = describeReturnCode(item.returnCode);
            errors[c.range] ??= new PlcError(code, text, { plcCode: item.returnCode });
          } else if (item.data.length !== c.length) {
            errors[c.range] ??= new ProtocolError(`${this.name}: ${c.length} bytes asked, ${item.data.length} returned`);
          } else {
            item.data.copy(buffers[c.range]!, c.offset);
          }
        });
      }),
    );
    const values: TagResult<PlcValue>[] = new Array(tags.length);
    plan.ranges.forEach((r, ri) => {
      const err = errors[ri];
      for (const i of r.tags) {
        const tag = tags[i]!;
        if (err) {
          values[i] = { ok: false, error: tagError(tag, err) };
          continue;
        }
        try {
          const ct = tag.area === 'C' || tag.area === 'T';
          const offset = ct ? (tag.byteOffset - r.start) * 2 : tag.byteOffset - r.start;
          values[i] = { ok: true, value: decodeTag(tag, buffers[ri]!, offset) };
        } catch (e) {
          values[i] = { ok: false, error: tagError(tag, toPlcError(e, 'PROTOCOL_ERROR')) };
        }
      }
    });
    return { values, rangeOk: errors.map((e) => e === undefined) };
  }

  protected async writeTags(session: S7Session, items: readonly { tag: Tag; value: unknown }[], signal?: AbortSignal): Promise<TagResult<void>[]> {
    const results: TagResult<void>[] = new Array(items.length);
    const valid: { tag: Tag; value: unknown }[] = [];
    const index: number[] = [];
    items.forEach((it, i) => {
      try {
        validateValue(it.tag, it.value);
        valid.push(it);
        index.push(i);
      } catch (err) {
        results[i] = { ok: false, error: toPlcError(err, 'INVALID_VALUE') };
      }
    });
    if (valid.length === 0) return results;
    const plan = planWrite(valid, session.pduSize);
    const errors: (PlcError | undefined)[] = valid.map(() => undefined);
    await Promise.all(
      plan.pdus.map(async (chunks) => {
        let answer: S7Message;
        try {
          answer = await this.request(session, (ref) => encodeWriteRequest(ref, chunks.map((c) => c.item)), `write of ${chunks.length} item(s)`, signal);
        } catch (err) {
          // The write may or may not have reached the PLC: report it on each of its tags, never drop it.
          for (const c of chunks) errors[c.tag] ??= toPlcError(err);
          return;
        }
        if (answer.kind === 'error') {
          const err = headerError(answer.errorClass, answer.errorCode, `${this.name} write`);
          for (const c of chunks) errors[c.tag] ??= err;
          return;
        }
        if (answer.kind !== 'write-ack' || answer.returnCodes.length !== chunks.length) {
          const err = new ProtocolError(`${this.name}: the answer to a write of ${chunks.length} item(s) does not match it`);
          for (const c of chunks) errors[c.tag] ??= err;
          return;
        }
        chunks.forEach((c, i) => {
          const rc = answer.returnCodes[i]!;
          if (rc !== 0xff) {
            const { code, text } = describeReturnCode(rc);
            errors[c.tag] ??= new PlcError(code, text, { plcCode: rc });
          }
        });
      }),
    );
    valid.forEach((it, k) => {
      const err = errors[k];
      results[index[k]!] = err ? { ok: false, error: tagError(it.tag, err) } : { ok: true, value: undefined };
    });
    return results;
  }
}

/** The same error, re-issued for one tag: names the tag, its canonical address and keeps the code. */
function tagError(tag: Tag, err: PlcError): PlcError {
  const where = `${tag.area === 'DB' ? `DB${tag.dbNumber}` : tag.area} byte ${tag.byteOffset}${tag.type === 'BOOL' ? `.${tag.bitOffset}` : ''}`;
  const rc = err.plcCode !== undefined && err.plcCode <= 0xff ? ` (return code 0x${err.plcCode.toString(16).padStart(2, '0')})` : '';
  return new PlcError(err.code, `${tag.address} (${where}): ${err.message}${rc}`, {
    tag: tag.address,
    ...(err.plcCode === undefined ? {} : { plcCode: err.plcCode }),
    cause: err,
  });
}

function hex4(n: number): string {
  return n.toString(16).toUpperCase().padStart(4, '0');
}

/**
 * Reads whole frames from a socket during the handshake; each call resolves
 * the next frame, rejects on close/error/abort. `stop()` detaches.
 */
function frameWaiter(socket: net.Socket, reader: FrameReader, signal: AbortSignal, name: string): (() => Promise<Buffer>) & { stop(): void } {
  const frames: Buffer[] = [];
  let waiting: { resolve: (b: Buffer) => void; reject: (e: Error) => void } | undefined;
  let failure: Error | undefined;
  const onData = (chunk: Buffer) => {
    try {
      frames.push(...reader.push(chunk));
    } catch (err) {
      failure = toPlcError(err, 'PROTOCOL_ERROR');
    }
    flush();
  };
  const onClose = () => {
    failure ??= new ConnectionError('CONNECT_FAILED', `${name} closed the connection during the handshake (wrong rack/slot or TSAP, or the connection limit is reached)`);
    flush();
  };
  const onError = (err: Error) => {
    failure ??= new ConnectionError('CONNECT_FAILED', `${name}: ${err.message}`, { cause: err });
    flush();
  };
  const onAbort = () => {
    failure ??= abortError(`connecting to ${name}`, signal);
    flush();
  };
  function flush() {
    if (!waiting) return;
    const w = waiting;
    if (frames.length > 0) {
      waiting = undefined;
      w.resolve(frames.shift()!);
    } else if (failure) {
      waiting = undefined;
      w.reject(failure);
    }
  }
  socket.on('data', onData);
  socket.on('close', onClose);
  socket.on('error', onError);
  signal.addEventListener('abort', onAbort, { once: true });
  const next = () =>
    new Promise<Buffer>((resolve, reject) => {
      waiting = { resolve, reject };
      flush();
    });
  return Object.assign(next, {
    stop() {
      socket.removeListener('data', onData);
      socket.removeListener('close', onClose);
      socket.removeListener('error', onError);
      signal.removeEventListener('abort', onAbort);
    },
  });
}
