/**
 * BOOL tags: `count` bits from bit `bitOffset` of the first byte, bit 0 being
 * the least significant (S7 bit addressing, X0.0..X0.7 then X1.0).
 */
import type { TagShape } from './types-table';

export function decodeBits(tag: TagShape, data: Buffer, offset: number): boolean[] {
  const bits: boolean[] = new Array<boolean>(tag.count);
  for (let i = 0; i < tag.count; i++) {
    const n = tag.bitOffset + i;
    bits[i] = (data[offset + (n >> 3)]! & (1 << (n & 7))) !== 0;
  }
  return bits;
}

/** Sets or clears only the tag's bits; every neighbouring bit keeps its value. */
export function encodeBits(tag: TagShape, bits: readonly boolean[], target: Buffer, offset: number): void {
  bits.forEach((on, i) => {
    const n = tag.bitOffset + i;
    const at = offset + (n >> 3);
    const mask = 1 << (n & 7);
    target[at] = on ? target[at]! | mask : target[at]! & ~mask;
  });
}
