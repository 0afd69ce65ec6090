/**
 * shortestFloat32: REAL values with the digits TIA Portal shows. Checked
 * against an exact reckoning of its own (BigInt, from the float32's bits):
 * the result reads back as the same float32, and no decimal with fewer
 * significant digits does.
 */
import { expect } from 'chai';
import fc from 'fast-check';
import { shortestFloat32 } from '../lib/values/float32';

const f32 = new Float32Array(1);
const u32 = new Uint32Array(f32.buffer);

function fromBits(bits: number): number {
  u32[0] = bits >>> 0;
  return f32[0]!;
}

/** The float32 `x` (positive, finite) as an exact fraction num/den. */
function exact(x: number): { num: bigint; den: bigint } {
  f32[0] = x;
  const bits = u32[0]!;
  const biased = (bits >>> 23) & 0xff;
  const mantissa = BigInt((bits & 0x7fffff) | (biased === 0 ? 0 : 0x800000));
  const e = (biased === 0 ? 1 : biased) - 127 - 23;
  return e >= 0 ? { num: mantissa << BigInt(e), den: 1n } : { num: mantissa, den: 1n << BigInt(-e) };
}

/** The two decimals of `digits` significant digits around `x` (positive): below or at it, and the next one up. */
function bracket(x: number, digits: number): [number, number] {
  const { num, den } = exact(x);
  let d = Math.floor(Math.log10(x)) - (digits - 1);
  const scaled = (k: number) => (k >= 0 ? num / (den * 10n ** BigInt(k)) : (num * 10n ** BigInt(-k)) / den);
  let q = scaled(d);
  while (q >= 10n ** BigInt(digits)) q = scaled(++d);
  while (q < 10n ** BigInt(digits - 1)) q = scaled(--d);
  return [Number(`${q}e${d}`), Number(`${q + 1n}e${d}`)];
}

function significantDigits(n: number): number {
  const mantissa = Math.abs(n).toExponential().split('e')[0]!;
  return mantissa.replace('.', '').length;
}

/** Asserts what shortestFloat32 promises for the finite float32 `x`. */
function check(x: number): void {
  const out = shortestFloat32(x);
  const text = String(out);
  expect(Math.fround(Number(text)), `${x} → ${text}`).to.equal(x);
  expect(Object.is(Math.sign(out), Math.sign(x)) || (x === 0 && out === 0), `${x} → ${text}: sign`).to.equal(true);
  if (x === 0) return;
  const digits = significantDigits(out);
  expect(digits, `${x} → ${text}`).to.be.at.most(9);
  for (let k = 1; k < digits; k++) {
    for (const shorter of bracket(Math.abs(x), k)) {
      expect(Math.fround(shorter), `${x} → ${text}, but ${shorter} (${k} digits) reads back the same`).to.not.equal(Math.abs(x));
    }
  }
}

describe('shortestFloat32: a REAL with the fewest digits that read back as the same float32', () => {
  it('gives the numbers TIA shows for values typed there', () => {
    const typed = [40.4, 0.1, 1e-7, 20, 12.5, -3.3, 100.01, 3.14159, 1e10, 123456.7, 0.3, -0.7];
    for (const n of typed) expect(shortestFloat32(Math.fround(n)), String(n)).to.equal(n);
    expect(Math.fround(40.4)).to.equal(40.400001525878906);
    expect(String(shortestFloat32(Math.fround(40.4)))).to.equal('40.4');
  });

  it('keeps the edges: the smallest subnormal, the largest REAL, 2^24, zeros, NaN and the infinities', () => {
    expect(shortestFloat32(fromBits(1))).to.equal(1e-45);
    expect(shortestFloat32(fromBits(0x7f7fffff))).to.equal(3.4028235e38);
    expect(shortestFloat32(-fromBits(0x7f7fffff))).to.equal(-3.4028235e38);
    expect(shortestFloat32(16777216)).to.equal(16777216);
    expect(shortestFloat32(fromBits(0x00800000))).to.equal(1.1754944e-38); // the smallest normal
    expect(Object.is(shortestFloat32(-0), -0)).to.equal(true);
    expect(Object.is(shortestFloat32(0), 0)).to.equal(true);
    expect(shortestFloat32(NaN)).to.be.NaN;
    expect(shortestFloat32(Infinity)).to.equal(Infinity);
    expect(shortestFloat32(-Infinity)).to.equal(-Infinity);
  });

  it('leaves a number that is no float32 as it is (an LREAL is printed as JavaScript prints it)', () => {
    for (const n of [0.1, 40.4, Math.PI, 1e300, 2 ** 53 + 2]) expect(shortestFloat32(n)).to.equal(n);
  });

  it('powers of two, where the float32 below is half as far as the one above', () => {
    for (let e = -149; e <= 127; e++) check(2 ** e);
  });

  it('any float32 bit pattern (finite): reads back as the same float32, and no shorter decimal does', () => {
    fc.assert(
      fc.property(fc.integer({ min: 0, max: 0xffffffff }), (bits) => {
        const x = fromBits(bits);
        if (!Number.isFinite(x)) return;
        check(x);
      }),
      { numRuns: 20000 },
    );
  });
});
