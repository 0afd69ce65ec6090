/**
 * FetchWriteClient: FETCH/WRITE to a CP's two passive connections ("Fetch
 * passive" and "Write passive", one port each, or one port for both) on the
 * shared link layer. The protocol has no request ids, so each connection has
 * one job at a time and the client runs jobs one after another; that also
 * serialises the read-modify-write of bits and odd DB bytes.
 *
 * Read-modify-write (bit writes, and byte writes at odd offsets of a DB
 * addressed in words) fetches the enclosing byte or word, changes the bits
 * or bytes, and writes it back. It is not atomic against the PLC program: a
 * change the program makes to the same byte/word in between is overwritten.
 * Likewise a value split over several jobs (beyond the ORG's length range) is
 * written job by job; if the link fails in between, part of it is written and
 * the tag's result is an error.
 */
import type * as net from 'node:net';
import { S7_TAG_SYNTAX } from '../address';
import { AddressError, ConnectionError, isLinkError, PlcError, tagError, TimeoutError, toPlcError, type TagResult } from '../errors';
import { BaseClient, endpointOptions, type ClientOptions } from '../client/base';
import type { Driver } from '../link/driver';
import { FrameReader } from '../link/framer';
import { JobQueue } from '../link/jobs';
import { PendingRequests } from '../link/pending';
import { openTcp } from '../link/tcp';
import type { PlcValue, Protocol, Tag } from '../types';
import { FETCHWRITE_URLS, type FetchWriteEndpoint } from './url';
import { decodeTag, validateValue } from '../values';
import {
  HEADER,
  MAX_DATA,
  OpCode,
  ORG_RANGES,
  Org,
  checkResponse,
  decodeResponse,
  encodeRequest,
  errorFor,
  type FwResponse,
  type ResponseExpectation,
} from './codec';
import {
  byteSpan,
  checkReach,
  enclosingUnits,
  mergeRanges,
  planRead,
  planWrite,
  splitJobs,
  wireUnits,
  type ByteAddress,
  type ByteRange,
  type ReadPlan,
} from './plan';

class Channel {
  readonly pending = new PendingRequests<FwResponse>();
  readonly reader: FrameReader;
  /** The one job this connection waits for; cleared as soon as its answer is cut, so trailing bytes are caught. */
  expect: ResponseExpectation | undefined;

  constructor(readonly socket: net.Socket) {
    this.reader = new FrameReader(
      (buf) => {
        const verdict = checkResponse(buf, this.expect);
        if (verdict.kind === 'frame') this.expect = undefined;
        return verdict;
      },
      MAX_DATA + HEADER + 1,
    );
  }
}

class FwSession {
  readonly jobs: JobQueue;
  /** Set when the link failed: later jobs fail at once instead of waiting for their timeout. */
  lost: PlcError | undefined;
  constructor(
    readonly fetch: Channel,
    readonly write: Channel,
    maxQueued: number | undefined,
  ) {
    this.jobs = new JobQueue({ concurrency: 1, ...(maxQueued === undefined ? {} : { maxQueued }) });
  }
  destroy(): void {
    this.fetch.socket.destroy();
    this.write.socket.destroy();
  }
}

/** One FETCH or WRITE request: a range of bytes, with the data to write. */
interface Job {
  op: OpCode.FetchRequest | OpCode.WriteRequest;
  range: ByteRange;
  data?: Buffer;
}

export class FetchWriteClient extends BaseClient<FwSession, Tag, ReadPlan> {
  readonly protocol: Protocol = 'fetchwrite';
  readonly endpoint: FetchWriteEndpoint;
  /** Jobs sent, for diagnostics and tests. */
  readonly stats = { fetches: 0, writes: 0 };
  protected readonly driver: Driver<FwSession, Tag, ReadPlan> = {
    syntax: { ...S7_TAG_SYNTAX, parse: (address) => this.parseTag(address) },
    openSession: (signal) => this.openSession(signal),
    prepareRead: (tags) => planRead(tags, this.endpoint.dbUnit),
    readTags: (session, tags, signal, prepared) => this.readTags(session, tags, signal, prepared),
    writeTags: (session, items, signal) => this.writeTags(session, items, signal),
    noBlockLength:
      `${this.name}: FETCH/WRITE has no service that tells the length of a data block, so the symbols' layout cannot be ` +
      'checked against the PLC: names are read and written at the offsets of the sources, unchecked (strictSymbols refuses nothing)',
    isLinkError: endsRequest,
  };

  constructor(endpoint: FetchWriteEndpoint, options: Partial<ClientOptions> = {}) {
    super(endpointOptions(FETCHWRITE_URLS.name(endpoint), endpoint, options));
    this.endpoint = endpoint;
  }

  /** S7 address syntax, limited to what FETCH/WRITE can reach (plan.ts, checkReach). */
  private parseTag(address: string): Tag {
    const tag = S7_TAG_SYNTAX.parse(address);
    checkReach(tag, this.endpoint.dbUnit);
    return tag;
  }

  private async openSession(signal: AbortSignal): Promise<FwSession> {
    const e = this.endpoint;
    const open = (port: number) => openTcp({ host: e.host, port, timeout: this.timeout, signal });
    const fetchSocket = await open(e.fetchPort);
    let writeSocket: net.Socket;
    try {
      writeSocket = e.writePort === e.fetchPort ? fetchSocket : await open(e.writePort);
    } catch (err) {
      fetchSocket.destroy();
      throw err;
    }
    const fetch = new Channel(fetchSocket);
    const write = writeSocket === fetchSocket ? fetch : new Channel(writeSocket);
    const session = new FwSession(fetch, write, this.maxQueued);
    for (const channel of new Set([fetch, write])) this.attach(session, channel);
    return session;
  }

  private attach(session: FwSession, channel: Channel): void {
    const fail = this.attachStream(session, channel.socket, (err) => {
      session.lost ??= err;
      session.fetch.pending.rejectAll(err);
      session.write.pending.rejectAll(err);
      session.jobs.rejectAll(err);
      session.destroy();
    });
    channel.socket.on('data', (chunk: Buffer) => {
      let frames: Buffer[];
      try {
        frames = channel.reader.push(chunk);
      } catch (err) {
        return fail(toPlcError(err, 'PROTOCOL_ERROR'));
      }
      for (const frame of frames) {
        let response: FwResponse;
        try {
          response = decodeResponse(frame);
        } catch (err) {
          return fail(toPlcError(err, 'PROTOCOL_ERROR'));
        }
        channel.pending.resolve(1, response);
      }
    });
  }

  /** One job on one channel (the caller holds the session's job queue). */
  private async job(session: FwSession, { op, range, data }: Job, signal?: AbortSignal): Promise<Buffer> {
    if (session.lost) throw session.lost;
    const { org, dbNumber, start: startByte, length: bytes } = range;
    const channel = op === OpCode.FetchRequest ? session.fetch : session.write;
    const { start, length } = wireUnits(range, this.endpoint.dbUnit);
    const frame = encodeRequest({ op, org, dbNumber: org === Org.DB ? dbNumber : 0, start, length, ...(data ? { data } : {}) });
    channel.expect = { op, dataBytes: op === OpCode.FetchRequest ? bytes : 0 };
    const what = `${op === OpCode.FetchRequest ? 'fetch' : 'write'} of ${ORG_RANGES[org]!.name}${org === Org.DB ? dbNumber : ''} ${startByte}+${bytes}`;
    const answer = channel.pending.add(1, this.timeout, `${this.name} ${what}`, signal);
    if (op === OpCode.FetchRequest) this.stats.fetches++;
    else this.stats.writes++;
    channel.socket.write(frame);
    let response: FwResponse;
    try {
      response = await answer;
    } catch (err) {
      if (err instanceof TimeoutError || (err instanceof PlcError && err.code === 'ABORTED')) {
        // Without request ids a late answer would be taken for the next job's: drop the link.
        const lost = new ConnectionError('CONNECTION_LOST', `${this.name}: ${err.message}`, { cause: err });
        session.lost ??= lost;
        session.destroy();
        this.sessionLost(session, lost);
      }
      throw err;
    }
    if (response.error !== 0) throw errorFor(response.error, `${this.name} ${what}`);
    return response.data;
  }

  private async readTags(
    session: FwSession,
    tags: readonly Tag[],
    signal?: AbortSignal,
    prepared = planRead(tags, this.endpoint.dbUnit),
  ): Promise<TagResult<PlcValue>[]> {
    const results: TagResult<PlcValue>[] = new Array<TagResult<PlcValue>>(tags.length);
    const { unreadable, ranges } = prepared;
    for (const i of unreadable) results[i] = { ok: false, error: wrongDirection(tags[i]!, 'read') };
    await session.jobs.run(async () => {
      for (const range of ranges) {
        let data: Buffer | undefined;
        let error: PlcError | undefined;
        try {
          data = await this.fetchRange(session, range, signal);
        } catch (err) {
          const e = toPlcError(err);
          if (endsRequest(e)) throw e;
          error = e;
        }
        if (error && range.tags.length > 1) {
          // One bad tag must not fail its merged neighbours: fetch each alone.
          for (const i of range.tags) results[i] = await this.readOne(session, tags[i]!, signal);
          continue;
        }
        for (const i of range.tags) {
          const tag = tags[i]!;
          if (error) results[i] = { ok: false, error: tagError(tag.address, error) };
          else results[i] = this.decode(tag, data!, range.start);
        }
      }
    }, signal);
    return results;
  }

  private async readOne(session: FwSession, tag: Tag, signal?: AbortSignal): Promise<TagResult<PlcValue>> {
    const [range] = mergeRanges([tag], this.endpoint.dbUnit);
    try {
      const data = await this.fetchRange(session, range!, signal);
      return this.decode(tag, data, range!.start);
    } catch (err) {
      const e = toPlcError(err);
      if (endsRequest(e)) throw e;
      return { ok: false, error: tagError(tag.address, e) };
    }
  }

  private decode(tag: Tag, data: Buffer, rangeStart: number): TagResult<PlcValue> {
    try {
      return { ok: true, value: decodeTag(tag, data, byteSpan(tag)[0] - rangeStart) };
    } catch (err) {
      return { ok: false, error: tagError(tag.address, toPlcError(err, 'PROTOCOL_ERROR')) };
    }
  }

  /** Fetches a byte range, split into the jobs the ORG's length range and the frame allow (plan.ts, splitJobs). */
  private async fetchRange(session: FwSession, range: ByteRange, signal?: AbortSignal): Promise<Buffer> {
    const jobs = splitJobs(range, this.endpoint.dbUnit);
    const op = OpCode.FetchRequest;
    if (jobs.length === 1) return this.job(session, { op, range: jobs[0]! }, signal);
    const parts: Buffer[] = [];
    for (const part of jobs) parts.push(await this.job(session, { op, range: part }, signal));
    return Buffer.concat(parts);
  }

  private async writeTags(
    session: FwSession,
    items: readonly { tag: Tag; value: unknown }[],
    signal?: AbortSignal,
  ): Promise<TagResult<void>[]> {
    const results: TagResult<void>[] = new Array<TagResult<void>>(items.length);
    const valid: number[] = [];
    items.forEach((it, i) => {
      if (it.tag.area === 'PE') {
        results[i] = { ok: false, error: wrongDirection(it.tag, 'write') };
        return;
      }
      try {
        validateValue(it.tag, it.value);
        valid.push(i);
      } catch (err) {
        results[i] = { ok: false, error: toPlcError(err, 'INVALID_VALUE') };
      }
    });
    await session.jobs
      .run(async () => {
        for (const i of valid) {
          const { tag, value } = items[i]!;
          try {
            await this.writeOne(session, tag, value, signal);
            results[i] = { ok: true, value: undefined };
          } catch (err) {
            const e = toPlcError(err);
            results[i] = { ok: false, error: tagError(tag.address, e) };
            // The link is gone: the remaining writes fail with the same error, never silently.
            if (endsRequest(e)) {
              for (const k of valid) results[k] ??= { ok: false, error: tagError(items[k]!.tag.address, e) };
              return;
            }
          }
        }
      }, signal)
      .catch((err: unknown) => {
        const e = toPlcError(err);
        for (const k of valid) results[k] ??= { ok: false, error: tagError(items[k]!.tag.address, e) };
      });
    return results;
  }

  private async writeOne(session: FwSession, tag: Tag, value: unknown, signal?: AbortSignal): Promise<void> {
    const plan = planWrite(tag, value, this.endpoint.dbUnit);
    if (plan.kind === 'direct') return this.writeRange(session, plan.at, plan.data, signal);
    return this.readModifyWrite(session, plan.range, plan.change, signal);
  }

  /** Fetch the enclosing units, change them, write them back (serialised by the job queue; not atomic against the PLC program). */
  private async readModifyWrite(
    session: FwSession,
    changed: ByteRange,
    change: (buf: Buffer, offset: number) => void,
    signal?: AbortSignal,
  ): Promise<void> {
    const units = enclosingUnits(changed, this.endpoint.dbUnit);
    const current = Buffer.from(await this.fetchRange(session, units, signal));
    change(current, changed.start - units.start);
    await this.writeRange(session, units, current, signal);
  }

  private async writeRange(session: FwSession, at: ByteAddress, data: Buffer, signal?: AbortSignal): Promise<void> {
    if (data.length === 0) return;
    let o = 0;
    for (const range of splitJobs({ ...at, length: data.length }, this.endpoint.dbUnit)) {
      const part = data.subarray(o, o + range.length);
      o += range.length;
      await this.job(session, { op: OpCode.WriteRequest, range, data: part }, signal);
    }
  }
}

/** ORG 5 fetches from input modules (PE) and writes to output modules (PA); the other direction does not exist. */
function wrongDirection(tag: Tag, op: 'read' | 'write'): PlcError {
  return new AddressError(
    tag.address,
    op === 'read'
      ? 'FETCH/WRITE cannot read back the output modules (ORG 5 fetches the input modules): read PI/PE addresses, write PQ/PA addresses'
      : 'FETCH/WRITE cannot write the input modules (ORG 5 writes the output modules): write PQ/PA addresses',
  );
}

/**
 * Errors that fail the whole request rather than a tag: the link's, and
 * those that drop a FETCH/WRITE link. Answers carry no request id, so a
 * job that timed out or was aborted, or a frame that does not parse, leaves
 * the connection unusable (FetchWriteClient.job); QUEUE_FULL refuses the
 * request before any job.
 */
function endsRequest(e: PlcError): boolean {
  return isLinkError(e) || e.code === 'TIMEOUT' || e.code === 'ABORTED' || e.code === 'PROTOCOL_ERROR' || e.code === 'QUEUE_FULL';
}
