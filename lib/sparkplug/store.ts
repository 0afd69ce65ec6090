/**
 * Store-and-forward (Sparkplug 3.0, section 5.17 "Historical data"): what a
 * device reported while the edge node had no Sparkplug session (broker away,
 * or primary host offline) is kept, in order, and sent after the next births
 * as historical metrics (is_historical true, their own timestamps). Bounded in
 * metrics and bytes: at the bound the oldest go first, and what was dropped
 * is counted. With `dir`, what is kept is also appended to a file there
 * (one line per value: the device and the value as a Sparkplug payload in
 * base64) and read back by the next store of the same edge node, so a
 * restarted process still forwards it.
 */
import * as fs from 'node:fs';
import * as path from 'node:path';
import { PlcError } from '../errors';
import type { SparkplugMetric } from './model';
import { decodePayload, encodePayload } from './payload';

export interface BufferOptions {
  /** Most metric values kept (default 10000). */
  count?: number;
  /** Most bytes kept, as the values' encoded size estimates (default 10 MB). */
  bytes?: number;
  /** A directory to keep them in across restarts of the edge node (else in memory only). */
  dir?: string;
}

interface Entry {
  device: string;
  metric: SparkplugMetric;
  bytes: number;
}

export class ForwardStore {
  private readonly maxCount: number;
  private readonly maxBytes: number;
  private entries: Entry[] = [];
  private head = 0;
  private size = 0;
  /** Metric values dropped at the bound since the start. */
  dropped = 0;

  private readonly file: string | undefined;

  /** `name` tells one edge node's file from another's in the same directory. */
  constructor(options: BufferOptions = {}, name = 'buffer') {
    this.maxCount = options.count ?? 10_000;
    this.maxBytes = options.bytes ?? 10_000_000;
    if (options.dir === undefined) return;
    fs.mkdirSync(options.dir, { recursive: true });
    this.file = path.join(options.dir, `${name}.buffer.ndjson`);
    const kept = readFile(this.file);
    fs.writeFileSync(this.file, '');
    for (const { device, metric } of kept) this.add(device, [metric]);
  }

  get count(): number {
    return this.entries.length - this.head;
  }

  get bytes(): number {
    return this.size;
  }

  /** Keeps a device's changed metrics; returns how many older ones it dropped to make room. */
  add(device: string, metrics: readonly SparkplugMetric[]): number {
    let dropped = 0;
    if (this.maxCount === 0) {
      this.dropped += metrics.length;
      return metrics.length;
    }
    for (const metric of metrics) {
      const bytes = estimateBytes(metric);
      this.entries.push({ device, metric, bytes });
      if (this.file) fs.appendFileSync(this.file, lineOf(device, metric));
      this.size += bytes;
      while (this.count > this.maxCount || (this.size > this.maxBytes && this.count > 0)) {
        this.size -= this.entries[this.head]!.bytes;
        this.head++;
        dropped++;
      }
    }
    if (this.head > 1024 && this.head * 2 > this.entries.length) {
      this.entries = this.entries.slice(this.head);
      this.head = 0;
      if (this.file) fs.writeFileSync(this.file, this.entries.map((e) => lineOf(e.device, e.metric)).join(''));
    }
    this.dropped += dropped;
    return dropped;
  }

  /**
   * Takes what is kept of the devices `which` accepts, oldest first, grouped into runs of one device each
   * (so order across devices holds); the other devices' values stay, in their order, for a later take.
   */
  take(which: (device: string) => boolean): { device: string; metrics: SparkplugMetric[] }[] {
    const out: { device: string; metrics: SparkplugMetric[] }[] = [];
    const kept: Entry[] = [];
    for (let i = this.head; i < this.entries.length; i++) {
      const e = this.entries[i]!;
      if (!which(e.device)) {
        kept.push(e);
        continue;
      }
      const last = out[out.length - 1];
      const metric = { ...e.metric, isHistorical: true };
      if (last && last.device === e.device) last.metrics.push(metric);
      else out.push({ device: e.device, metrics: [metric] });
    }
    if (out.length === 0) return out;
    this.entries = kept;
    this.head = 0;
    this.size = kept.reduce((n, e) => n + e.bytes, 0);
    if (this.file) fs.writeFileSync(this.file, kept.map((e) => lineOf(e.device, e.metric)).join(''));
    return out;
  }
}

/** A metric's encoded size, roughly: tag bytes, alias, timestamp, datatype and its value. */
function estimateBytes(m: SparkplugMetric): number {
  const v = m.value;
  let value = 9;
  if (typeof v === 'string') value = Buffer.byteLength(v) + 2;
  else if (v instanceof Uint8Array) value = v.length + 3;
  else if (Array.isArray(v)) value = v.reduce<number>((n, x) => n + (typeof x === 'string' ? Buffer.byteLength(x) + 1 : 8), 3);
  return 2 + 4 + 7 + 2 + value;
}

function lineOf(device: string, metric: SparkplugMetric): string {
  return `${JSON.stringify({ device, payload: encodePayload({ metrics: [metric] }).toString('base64') })}\n`;
}

/** The values a file keeps, oldest first; a last line without its newline (a write cut short) is dropped, any other bad line is an error naming the file and line. */
function readFile(file: string): { device: string; metric: SparkplugMetric }[] {
  let text: string;
  try {
    text = fs.readFileSync(file, 'utf8');
  } catch (err) {
    if ((err as NodeJS.ErrnoException).code === 'ENOENT') return [];
    throw err;
  }
  const out: { device: string; metric: SparkplugMetric }[] = [];
  const lines = text.split('\n');
  lines.pop(); // '' after the last newline, or the last line a crash cut short: dropped
  lines.forEach((line, i) => {
    if (line === '') return;
    try {
      const { device, payload } = JSON.parse(line) as { device: string; payload: string };
      out.push({ device, metric: decodePayload(Buffer.from(payload, 'base64')).metrics[0]! });
    } catch (err) {
      throw new PlcError('INVALID_VALUE', `${file}:${i + 1}: not a stored Sparkplug value (${(err as Error).message})`, { cause: err });
    }
  });
  return out;
}
