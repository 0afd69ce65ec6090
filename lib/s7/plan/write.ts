import { toPlcError, type PlcError } from '../../errors';
import type { Tag } from '../../types';
import { validateValue, writeSpan } from '../../values';
import {
  DataTransportSize,
  MAX_ITEMS,
  READ_ITEM,
  S7Area,
  TransportSize,
  VAR_REQUEST_BASE,
  VAR_RESPONSE_BASE,
  WRITE_DATA_HEADER,
} from '../constants';
import { areaCode, isCounterOrTimer } from './atoms';
import { checkPduSize, maxWriteItemData, type PlanOptions } from './limits';

/** A Write Var item, shaped like the codec's write item. */
export interface PlannedWriteItem {
  area: number;
  dbNumber: number;
  transportSize: number;
  count: number;
  address: number;
  dataTransportSize: number;
  data: Buffer;
}

export interface WritePdu {
  items: PlannedWriteItem[];
  /** Per item: the index of its tag in the write. */
  tags: number[];
  requestSize: number;
  responseSize: number;
}

export interface WritePlan {
  pduSize: number;
  pdus: WritePdu[];
  /** Per tag: the ValueError that kept it out of the plan, if any. */
  errors: (PlcError | undefined)[];
}

/**
 * Plans a write. Each tag becomes its own items: bits as BIT items, one per
 * bit (the CPU writes a single bit atomically; no read-modify-write, so
 * neighbouring bits are never clobbered); STRING/WSTRING from the current
 * length byte(s) on (writeSpan: the PLC's declared max length stays); data
 * larger than one PDU is cut into chunks. Items are packed first-fit
 * decreasing. A value that does not fit its tag is reported in `errors` and
 * not sent.
 */
export function planWrite(
  writes: readonly { tag: Tag; value: unknown }[],
  pduSize: number,
  options: Pick<PlanOptions, 'maxItems'> = {},
): WritePlan {
  checkPduSize(pduSize);
  const maxData = maxWriteItemData(pduSize);
  const maxItems = Math.min(options.maxItems ?? MAX_ITEMS, MAX_ITEMS, pduSize - VAR_RESPONSE_BASE);
  const pieces: { tag: number; item: PlannedWriteItem }[] = [];
  const errors: (PlcError | undefined)[] = writes.map(() => undefined);
  writes.forEach(({ tag, value }, index) => {
    try {
      pieces.push(...writeItems(tag, value, maxData).map((item) => ({ tag: index, item })));
    } catch (err) {
      errors[index] = toPlcError(err, 'INVALID_VALUE');
    }
  });
  pieces.sort((a, b) => b.item.data.length - a.item.data.length);
  const bins: { pdu: WritePdu; lastOdd: boolean }[] = [];
  for (const p of pieces) {
    const len = p.item.data.length;
    let bin = bins.find(
      (b) => b.pdu.items.length < maxItems && b.pdu.requestSize + READ_ITEM + (b.lastOdd ? 1 : 0) + WRITE_DATA_HEADER + len <= pduSize,
    );
    if (!bin) {
      bin = { pdu: { items: [], tags: [], requestSize: VAR_REQUEST_BASE, responseSize: VAR_RESPONSE_BASE }, lastOdd: false };
      bins.push(bin);
    }
    bin.pdu.requestSize += READ_ITEM + (bin.lastOdd ? 1 : 0) + WRITE_DATA_HEADER + len;
    bin.pdu.responseSize += 1;
    bin.pdu.items.push(p.item);
    bin.pdu.tags.push(p.tag);
    bin.lastOdd = len % 2 === 1;
  }
  return { pduSize, pdus: bins.map((b) => b.pdu), errors };
}

function writeItems(tag: Tag, value: unknown, maxData: number): PlannedWriteItem[] {
  const area = areaCode(tag);
  validateValue(tag, value);
  if (tag.type === 'BOOL') {
    const bits = tag.isArray ? (value as readonly boolean[]) : [value as boolean];
    return bits.map((bit, i) => {
      const n = tag.bitOffset + i;
      return {
        area,
        dbNumber: tag.dbNumber,
        transportSize: TransportSize.BIT,
        count: 1,
        address: (tag.byteOffset + (n >> 3)) * 8 + (n & 7),
        dataTransportSize: DataTransportSize.BIT,
        data: Buffer.of(bit ? 1 : 0),
      };
    });
  }
  const { start, data } = writeSpan(tag, value);
  const items: PlannedWriteItem[] = [];
  if (isCounterOrTimer(area)) {
    const step = maxData - (maxData % 2);
    const transportSize = area === S7Area.C ? TransportSize.COUNTER : TransportSize.TIMER;
    for (let o = 0; o < data.length; o += step) {
      const part = data.subarray(o, o + step);
      items.push({
        area,
        dbNumber: 0,
        transportSize,
        count: part.length / 2,
        address: tag.byteOffset + o / 2,
        dataTransportSize: DataTransportSize.OCTET_STRING,
        data: part,
      });
    }
    return items;
  }
  for (let o = 0; o < data.length; o += maxData) {
    const part = data.subarray(o, o + maxData);
    items.push({
      area,
      dbNumber: tag.dbNumber,
      transportSize: TransportSize.BYTE,
      count: part.length,
      address: (tag.byteOffset + start + o) * 8,
      dataTransportSize: DataTransportSize.BYTE,
      data: part,
    });
  }
  return items;
}
