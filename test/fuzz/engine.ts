/**
 * A small mutation fuzzer for the decoders (`npm run fuzz`): random bytes,
 * and mutations of valid seed frames (bit flips, truncation, extension,
 * length fields overwritten with hostile values). A decoder may return or
 * throw a PlcError; anything else is a finding.
 */
import { PlcError } from '../../lib/errors';

export interface FuzzTarget {
  name: string;
  /** Valid inputs to mutate (published frames from test/fixtures and our encoders). */
  seeds: Buffer[];
  run(input: Buffer): void;
}

export interface FuzzResult {
  name: string;
  inputs: number;
  accepted: number;
  typedErrors: number;
  /** Inputs that threw something other than a PlcError (the first 10 are kept). */
  findingCount: number;
  findings: { input: string; error: string }[];
  ms: number;
}

/** xorshift32: fast and repeatable from a seed. */
export function rng(seed: number): () => number {
  let x = seed >>> 0 || 0x9e3779b9;
  return () => {
    x ^= x << 13;
    x >>>= 0;
    x ^= x >>> 17;
    x ^= x << 5;
    x >>>= 0;
    return x;
  };
}

const HOSTILE = [0x00, 0x01, 0x02, 0x03, 0x04, 0x07, 0x7f, 0x80, 0xfe, 0xff];

export function mutate(seed: Buffer, next: () => number): Buffer {
  const pick = next() % 6;
  const r = (n: number) => (n <= 0 ? 0 : next() % n);
  switch (pick) {
    case 0: {
      const out = Buffer.allocUnsafe(r(96));
      for (let i = 0; i < out.length; i++) out[i] = next() & 0xff;
      return out;
    }
    case 1: {
      const out = Buffer.from(seed);
      for (let k = 1 + r(4); k > 0 && out.length > 0; k--) out[r(out.length)]! ^= 1 << r(8);
      return out;
    }
    case 2:
      return seed.subarray(0, r(seed.length + 1));
    case 3: {
      const extra = Buffer.allocUnsafe(1 + r(32));
      for (let i = 0; i < extra.length; i++) extra[i] = next() & 0xff;
      return Buffer.concat([seed, extra]);
    }
    case 4: {
      const out = Buffer.from(seed);
      for (let k = 1 + r(3); k > 0 && out.length > 0; k--) out[r(out.length)] = HOSTILE[r(HOSTILE.length)]!;
      return out;
    }
    default: {
      const out = Buffer.from(seed);
      if (out.length >= 2) out.writeUInt16BE(next() & 1 ? 0xffff : r(0x10000), r(out.length - 1));
      return out;
    }
  }
}

export function fuzz(target: FuzzTarget, inputs: number, seed = 1): FuzzResult {
  const next = rng(seed);
  const result: FuzzResult = { name: target.name, inputs, accepted: 0, typedErrors: 0, findingCount: 0, findings: [], ms: 0 };
  const started = process.hrtime.bigint();
  for (let i = 0; i < inputs; i++) {
    const base = target.seeds.length > 0 ? target.seeds[next() % target.seeds.length]! : Buffer.alloc(0);
    const input = mutate(base, next);
    try {
      target.run(input);
      result.accepted++;
    } catch (err) {
      if (err instanceof PlcError) result.typedErrors++;
      else if (++result.findingCount <= 10)
        result.findings.push({ input: input.toString('hex'), error: String((err as Error)?.stack ?? err) });
    }
  }
  result.ms = Number(process.hrtime.bigint() - started) / 1e6;
  return result;
}
