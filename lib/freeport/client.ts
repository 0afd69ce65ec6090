/**
 * The freeport master: reads and writes the 4-byte data areas of S7-200
 * stations on an RS-485 bus, over a serial port or a serial device server.
 *
 * - Several tags of one station in one read cost one request.
 * - A write that starts at byte 0 and is not a bit is sent as it is (LE = its
 *   length). Any other write — a bit, or bytes not starting at byte 0 — is a
 *   read-modify-write of the whole area (LE = 4), done with the bus held, so
 *   nothing else reaches the station in between. Several writes to one
 *   station in one call are merged into one read-modify-write.
 * - The station answers a write with the data it now holds; unless the
 *   profile says `verifyWrites: false`, the written bytes must be there.
 */
import type { BindingInterface } from '@serialport/bindings-interface';
import * as net from 'node:net';
import type { SerialPortStream } from '@serialport/stream';
import { spanContains } from '../address/syntax';
import { ConnectionError, isLinkError, PlcError, toPlcError, type TagResult } from '../errors';
import { BaseClient, endpointOptions, type ClientOptions } from '../client/base';
import type { Driver, TagSyntax } from '../link/driver';
import { closeSerial, openSerial } from '../link/serial';
import { openTcp } from '../link/tcp';
import type { PlcValue } from '../types';
import { FREEPORT_URLS, type FreeportEndpoint } from './url';
import { decodeTag, encodeInto, encodeTag } from '../values';
import { parseFreeportAddress, type FreeportTag } from './address';
import { readRequest, writeRequest, type FreeportReply } from './codec';
import { defineProfile, maxStation, type FreeportProfile } from './profile';
import { FreeportSession, type FreeportTransport } from './session';

export interface FreeportClientOptions extends Partial<ClientOptions> {
  /** A serialport binding other than the platform's (tests: `@serialport/binding-mock`). */
  binding?: BindingInterface;
  /** The frame profile of the stations' PLC program (default: DEFAULT_FREEPORT_PROFILE, docs/protocols.md). */
  profile?: Partial<FreeportProfile>;
}

/** What a prepared tag list keeps (Driver.prepareRead): its tags grouped by station, one read request each. */
type FreeportPrepared = [station: number, group: { tag: FreeportTag; i: number }[]][];

export class FreeportClient extends BaseClient<FreeportSession, FreeportTag, FreeportPrepared> {
  readonly protocol = 'freeport' as const;
  readonly endpoint: FreeportEndpoint;
  readonly profile: FreeportProfile;
  private readonly binding: BindingInterface | undefined;
  protected readonly driver: Driver<FreeportSession, FreeportTag, FreeportPrepared> = {
    syntax: {
      parse: (address) => parseFreeportAddress(address, { maxStation: maxStation(this.profile), dataBytes: this.profile.dataBytes }),
      ...STATION_AREAS,
    },
    openSession: (signal) => this.openSession(signal),
    prepareRead: (tags) => byStation(tags),
    readTags: (session, tags, signal, prepared) => this.readTags(session, tags, signal, prepared),
    writeTags: (session, items, signal) => this.writeTags(session, items, signal),
    // A silent or garbling station fails its own tags; only a lost line fails the whole request.
    isLinkError,
  };

  constructor(endpoint: FreeportEndpoint, options: FreeportClientOptions = {}) {
    const { binding, profile, ...common } = options;
    super(endpointOptions(FREEPORT_URLS.name(endpoint), endpoint, common));
    this.endpoint = endpoint;
    this.profile = defineProfile(profile);
    this.binding = binding;
  }

  /** Closes the line and resolves once the serial port or socket is released. */
  override async close(): Promise<void> {
    const session = this.session;
    await super.close();
    await session?.closed();
  }

  private async openSession(signal: AbortSignal): Promise<FreeportSession> {
    const t = this.endpoint.transport;
    const discipline = {
      name: this.name,
      timeout: this.timeout,
      retries: this.endpoint.retries,
      interFrameGapMs: this.endpoint.interFrameGapMs,
      ...(this.maxQueued ? { maxQueued: this.maxQueued } : {}),
    };
    if (t.kind === 'tcp') {
      const socket = await openTcp({ host: t.host, port: t.port, timeout: this.timeout, signal });
      const session = new FreeportSession(socketTransport(socket), this.profile, discipline);
      socket.on('data', (chunk) => session.receive(chunk));
      socket.on('error', () => {}); // 'close' follows and reports it
      socket.once('close', () =>
        this.lose(session, new ConnectionError('CONNECTION_LOST', `${this.name}: the serial device server closed the connection`)),
      );
      return session;
    }
    const port = await openSerial({ ...t, ...(this.binding ? { binding: this.binding } : {}), signal });
    const session = new FreeportSession(serialTransport(port), this.profile, discipline);
    port.on('data', (chunk: Buffer) => session.receive(chunk));
    port.once('close', (err: Error | null) =>
      this.lose(
        session,
        new ConnectionError('CONNECTION_LOST', `${this.name}: the serial port closed${err ? ` (${err.message})` : ''}`, {
          cause: err ?? undefined,
        }),
      ),
    );
    return session;
  }

  /** Pending requests fail with the real reason, then the supervisor reconnects. */
  private lose(session: FreeportSession, err: PlcError): void {
    session.destroy(err);
    this.sessionLost(session, err);
  }

  private async readTags(
    session: FreeportSession,
    tags: readonly FreeportTag[],
    signal?: AbortSignal,
    prepared = byStation(tags),
  ): Promise<TagResult<PlcValue>[]> {
    const results: TagResult<PlcValue>[] = new Array<TagResult<PlcValue>>(tags.length);
    await Promise.all(
      prepared.map(async ([station, group]) => {
        let reply: FreeportReply;
        try {
          reply = await session.exchange(readRequest(station, this.profile), signal);
        } catch (err) {
          const error = stationFailure(err);
          for (const { i } of group) results[i] = { ok: false, error };
          return;
        }
        for (const { tag, i } of group) {
          try {
            results[i] = { ok: true, value: decodeTag(tag, reply.data, tag.byteOffset) };
          } catch (err) {
            results[i] = { ok: false, error: toPlcError(err, 'PROTOCOL_ERROR') };
          }
        }
      }),
    );
    return results;
  }

  private async writeTags(
    session: FreeportSession,
    items: readonly { tag: FreeportTag; value: unknown }[],
    signal?: AbortSignal,
  ): Promise<TagResult<void>[]> {
    const results: TagResult<void>[] = new Array<TagResult<void>>(items.length);
    const valid: { tag: FreeportTag; value: unknown; i: number; bytes: Buffer }[] = [];
    items.forEach(({ tag, value }, i) => {
      try {
        valid.push({ tag, value, i, bytes: encodeTag(tag, value) });
      } catch (err) {
        results[i] = { ok: false, error: toPlcError(err, 'INVALID_VALUE') };
      }
    });
    await Promise.all(
      [...groupByStation(valid)].map(async ([station, group]) => {
        try {
          await this.writeStation(session, station, group, signal);
          for (const { i } of group) results[i] = { ok: true, value: undefined };
        } catch (err) {
          const error = stationFailure(err);
          for (const { i } of group) results[i] = { ok: false, error };
        }
      }),
    );
    return results;
  }

  private writeStation(
    session: FreeportSession,
    station: number,
    group: readonly { tag: FreeportTag; value: unknown; bytes: Buffer }[],
    signal?: AbortSignal,
  ): Promise<void> {
    const only = group.length === 1 ? group[0]! : undefined;
    if (only && only.tag.byteOffset === 0 && only.tag.type !== 'BOOL') {
      return session
        .exchange(writeRequest(station, only.bytes, this.profile), signal)
        .then((reply) => this.verify(station, only.bytes, reply));
    }
    return session.transaction(async (exchange) => {
      const before = await exchange(readRequest(station, this.profile));
      const area = Buffer.from(before.data);
      for (const { tag, value } of group) encodeInto(tag, value, area, tag.byteOffset);
      this.verify(station, area, await exchange(writeRequest(station, area, this.profile)));
    }, signal);
  }

  private verify(station: number, written: Buffer, reply: FreeportReply): void {
    if (!this.profile.verifyWrites) return;
    const held = reply.data.subarray(0, written.length);
    if (!held.equals(written)) {
      throw new PlcError(
        'PLC_ERROR',
        `station ${station} on ${this.name} did not take the write: sent ${hex(written)}, it holds ${hex(held)}`,
      );
    }
  }
}

/** A station's failure is its tags' result; a link error is thrown (the whole request failed). */
function stationFailure(err: unknown): PlcError {
  const error = toPlcError(err);
  if (isLinkError(error)) throw error;
  return error;
}

/** A station's data area is the area an allow-list names: "ST5". */
const STATION_AREAS: Omit<TagSyntax<FreeportTag>, 'parse'> = Object.freeze({
  areaOf: (tag: FreeportTag) => `ST${tag.station}`,
  allowArea: (entry: string) => (/^ST\d+$/.test(entry) ? entry.replace(/^ST0+(?=\d)/, 'ST') : undefined),
  contains: (outer: FreeportTag, inner: FreeportTag) => outer.station === inner.station && spanContains(outer, inner),
});

/** A read's tags by station, with their indexes. */
function byStation(tags: readonly FreeportTag[]): FreeportPrepared {
  return [...groupByStation(tags.map((tag, i) => ({ tag, i })))];
}

function groupByStation<I extends { tag: FreeportTag }>(items: readonly I[]): Map<number, I[]> {
  const groups = new Map<number, I[]>();
  for (const item of items) {
    const group = groups.get(item.tag.station);
    if (group) group.push(item);
    else groups.set(item.tag.station, [item]);
  }
  return groups;
}

function socketTransport(socket: net.Socket): FreeportTransport {
  return {
    write: (bytes) => void socket.write(bytes),
    destroy: () =>
      new Promise<void>((resolve) => {
        if (socket.destroyed) return resolve();
        socket.once('close', () => resolve());
        socket.destroy();
      }),
  };
}

function serialTransport(port: SerialPortStream): FreeportTransport {
  return {
    write: (bytes) => void port.write(bytes),
    destroy: () => closeSerial(port),
  };
}

function hex(bytes: Buffer): string {
  return bytes
    .toString('hex')
    .toUpperCase()
    .replace(/(..)(?!$)/g, '$1 ');
}
