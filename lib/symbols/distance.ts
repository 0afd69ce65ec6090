/** Edit distance for "did you mean": how far a typed name is from an existing one. */

/**
 * Optimal string alignment distance (Levenshtein with swapped neighbours as
 * one edit: `Levle` is one edit from `Level`), or `limit + 1` as soon as it
 * must exceed `limit`. Only the band |i - j| <= limit is computed.
 */
export function distance(a: string, b: string, limit: number): number {
  if (Math.abs(a.length - b.length) > limit) return limit + 1;
  if (a === b) return 0;
  const n = b.length;
  const big = limit + 1;
  if (rows.length < 3 * (n + 1)) rows = new Int32Array(6 * (n + 1));
  // Three rows in one buffer: i - 2, i - 1 and i, rotated by offset.
  const width = n + 1;
  let prev2 = 0;
  let prev = width;
  let row = 2 * width;
  rows.fill(big, 0, 3 * width);
  for (let j = 0; j <= Math.min(n, limit); j++) rows[prev + j] = j;
  for (let i = 1; i <= a.length; i++) {
    rows.fill(big, row, row + width);
    if (i <= limit) rows[row] = i;
    let best = rows[row]!;
    const from = Math.max(1, i - limit);
    const to = Math.min(n, i + limit);
    const ca = a.charCodeAt(i - 1);
    for (let j = from; j <= to; j++) {
      const cb = b.charCodeAt(j - 1);
      let d = Math.min(rows[prev + j]! + 1, rows[row + j - 1]! + 1, rows[prev + j - 1]! + (ca === cb ? 0 : 1));
      if (i > 1 && j > 1 && ca === b.charCodeAt(j - 2) && a.charCodeAt(i - 2) === cb) d = Math.min(d, rows[prev2 + j - 2]! + 1);
      rows[row + j] = d;
      if (d < best) best = d;
    }
    if (best > limit) return big;
    [prev2, prev, row] = [prev, row, prev2];
  }
  return Math.min(rows[prev + n]!, big);
}
/** distance()'s work space, grown as needed (distance() is synchronous: one user at a time). */
let rows = new Int32Array(256);
