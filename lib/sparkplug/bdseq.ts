/**
 * The birth/death sequence number (Sparkplug 3.0, section 4.1.2 "NBIRTH",
 * tck-id-topics-nbirth-bdseq-increment and
 * tck-id-message-flow-edge-node-birth-publish-will-message-payload-bdSeq):
 * 0 on the first MQTT CONNECT, +1 on every new one, 255 followed by 0. It is
 * kept in a file of the state directory so a restarted edge node goes on
 * counting (a host that sees bdSeq start again at 0 cannot tell the new
 * session's NDEATH from the old one's); the file is written before the
 * CONNECT that carries the number, atomically (a temporary file renamed).
 */
import * as fs from 'node:fs';
import * as path from 'node:path';
import { PlcError } from '../errors';

const MODULUS = 256;

export class BdSeqStore {
  private last: number | undefined;
  private readonly file: string | undefined;

  /** `dir` undefined: kept in memory only (restarts at 0 with the process). */
  constructor(dir: string | undefined, group: string, node: string) {
    this.file = dir === undefined ? undefined : path.join(dir, `${encodeURIComponent(group)}.${encodeURIComponent(node)}.bdseq.json`);
  }

  /** The bdSeq of the last CONNECT, undefined before the first one ever. */
  current(): number | undefined {
    if (this.last === undefined && this.file) this.last = readFile(this.file);
    return this.last;
  }

  /** The bdSeq of the next CONNECT, stored before it is used. */
  next(): number {
    const last = this.current();
    const next = last === undefined ? 0 : (last + 1) % MODULUS;
    if (this.file) writeFile(this.file, next);
    this.last = next;
    return next;
  }
}

function readFile(file: string): number | undefined {
  let text: string;
  try {
    text = fs.readFileSync(file, 'utf8');
  } catch (err) {
    if ((err as NodeJS.ErrnoException).code === 'ENOENT') return undefined;
    throw new PlcError('INVALID_VALUE', `cannot read the Sparkplug bdSeq file ${file}: ${(err as Error).message}`, { cause: err });
  }
  const value = (() => {
    try {
      return (JSON.parse(text) as { bdSeq?: unknown }).bdSeq;
    } catch {
      return undefined;
    }
  })();
  if (typeof value !== 'number' || !Number.isInteger(value) || value < 0 || value >= MODULUS) {
    throw new PlcError(
      'INVALID_VALUE',
      `the Sparkplug bdSeq file ${file} does not hold {"bdSeq": 0..255}: ${JSON.stringify(text.slice(0, 60))}`,
    );
  }
  return value;
}

function writeFile(file: string, bdSeq: number): void {
  fs.mkdirSync(path.dirname(file), { recursive: true });
  const tmp = `${file}.${process.pid}.tmp`;
  fs.writeFileSync(tmp, `${JSON.stringify({ bdSeq })}\n`);
  fs.renameSync(tmp, file);
}
