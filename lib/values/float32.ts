/**
 * REAL values as people read them: a float32 read from the PLC is a binary
 * fraction (40.4 is held as 40.400001525878906...), and JavaScript prints a
 * number with the digits that tell it apart among 64-bit floats. TIA Portal
 * shows 40.4: the fewest digits that tell the value apart among 32-bit floats.
 * shortestFloat32() gives that number: the shortest decimal that reads back
 * (Number(), then float32 as a REAL write does) as the very same float32.
 */

/** 10^0 .. 10^22: every one exact in a double, so m / 10^k and m * 10^k are the decimal's nearest double. */
const POW10 = Array.from({ length: 23 }, (_, k) => Number(`1e${k}`));
const EXACT = POW10.length - 1;

const SCIENTIFIC = /^(\d+)(?:\.(\d+))?(?:e([+-]\d+))?$/;

/**
 * For magnitudes beyond the exact powers of ten: the two decimals of
 * `precision` significant digits around `magnitude`, nearest first, parsed
 * from text.
 */
function bracketByText(magnitude: number, precision: number): number[] {
  const text = magnitude.toPrecision(precision);
  const nearest = Number(text);
  const m = SCIENTIFIC.exec(text);
  if (!m) return [nearest];
  const fraction = m[2] ?? '';
  const digits = BigInt(m[1]! + fraction) + (nearest < magnitude ? 1n : -1n);
  if (digits <= 0n) return [nearest];
  return [nearest, Number(`${digits}e${Number(m[3] ?? 0) - fraction.length}`)];
}

/**
 * The number with the shortest decimal form (1 to 9 significant digits) that
 * is the same float32 as `value`: 40.400001525878906 → 40.4,
 * 0.10000000149011612 → 0.1, 1.401298464324817e-45 → 1e-45. Of the two
 * decimals with that many digits around the value, the nearer one when both
 * read back. Zero (-0 too), NaN and ±Infinity are returned as they are, and
 * so is a number that is no float32 (an LREAL's 0.1 is not shortened).
 *
 * At each precision only the two decimals around the value can read back
 * (the values that round to a float32 form an interval around it); both are
 * tried, since at a power of two the interval reaches twice as far above as
 * below.
 */
export function shortestFloat32(value: number): number {
  if (value === 0 || !Number.isFinite(value) || Math.fround(value) !== value) return value;
  const magnitude = Math.abs(value);
  let exponent = Math.floor(Math.log10(magnitude));
  // log10 may be one off near a power of ten.
  if (magnitude < 10 ** exponent) exponent--;
  else if (magnitude >= 10 ** (exponent + 1)) exponent++;
  for (let precision = 1; precision <= 9; precision++) {
    const k = exponent - precision + 1;
    if (k < -EXACT || k > EXACT) {
      for (const c of bracketByText(magnitude, precision)) if (Math.fround(c) === magnitude) return value < 0 ? -c : c;
      continue;
    }
    const scale = POW10[k < 0 ? -k : k]!;
    const scaled = k < 0 ? magnitude * scale : magnitude / scale;
    const m = Math.round(scaled);
    const near = k < 0 ? m / scale : m * scale;
    if (Math.fround(near) === magnitude) return value < 0 ? -near : near;
    const m2 = scaled < m ? m - 1 : m + 1;
    const other = k < 0 ? m2 / scale : m2 * scale;
    if (Math.fround(other) === magnitude) return value < 0 ? -other : other;
  }
  // Nine significant digits always tell float32s apart (IEEE 754-2008, 5.12.2): not reached.
  return value;
}
