/**
 * A DAI (codec/alarms.ts) as the one alarm model (lib/alarms/model.ts): the
 * associated values decoded by the Softdatatype their blob's root id names,
 * the texts per language (LCID to `en-US`) with the values put in their
 * placeholders (`@1%d@`: SD_1 in C printf's format, as TIA writes them), and
 * the reverse for the simulator (a value to its blob).
 *
 * Sources: s7commplus (MIT) alarm.py (_decode_associated_value: the root ids
 * 0x02000000 + Softdatatype, STRING 0x020A0000–0x020AFFFF with max and
 * actual length bytes, WSTRING 0x020B0000–0x020BFFFF with UInt16 lengths and
 * UTF-16BE; _ASSOCIATED_VALUE_TOKEN; LanguageId, the Windows LCIDs);
 * S7CommPlusDriver (LGPL; facts only) AlarmsAssociatedValues.cs (element 0 a
 * type information, SD_1 at element 1).
 */
import type { AlarmTexts, AlarmValue, PlcAlarm } from '../../alarms/model';
import type { PlcValue } from '../../types';
import { ASSOCIATED_VALUES, TextId, type Dai } from './alarms';
import type { BlobValue } from './pvalue';

/** Windows LCIDs of the languages TIA offers (alarm.py LanguageId), by BCP 47 tag. */
const LCIDS: Readonly<Record<string, number>> = {
  'zh-TW': 1028,
  'cs-CZ': 1029,
  'da-DK': 1030,
  'de-DE': 1031,
  'el-GR': 1032,
  'en-US': 1033,
  'es-ES': 1034,
  'fi-FI': 1035,
  'fr-FR': 1036,
  'hu-HU': 1038,
  'it-IT': 1040,
  'ja-JP': 1041,
  'ko-KR': 1042,
  'nl-NL': 1043,
  'pl-PL': 1045,
  'pt-BR': 1046,
  'ru-RU': 1049,
  'sv-SE': 1053,
  'tr-TR': 1055,
  'zh-CN': 2052,
  'nl-BE': 2067,
  'pt-PT': 2070,
};

const TAGS = new Map(Object.entries(LCIDS).map(([tag, id]) => [id, tag]));

/** The LCID of a language tag (`en-US`, `de`, or a number as text); undefined when not known. */
export function lcidOf(language: string): number | undefined {
  if (/^\d+$/.test(language)) return Number(language);
  const l = language.trim().toLowerCase();
  for (const [tag, id] of Object.entries(LCIDS)) if (tag.toLowerCase() === l || tag.slice(0, 2).toLowerCase() === l) return id;
  return undefined;
}

/** The tag of an LCID (`en-US`), or the LCID in decimal when it is none of TIA's. */
function languageOf(lcid: number): string {
  return TAGS.get(lcid) ?? String(lcid);
}

const ROOT = 0x02000000;
/** Softdatatypes an associated value may have (the types TIA allows for SD_n), by our type name. */
const SOFT: Readonly<Record<string, number>> = {
  BOOL: 1,
  BYTE: 2,
  CHAR: 3,
  WORD: 4,
  INT: 5,
  DWORD: 6,
  DINT: 7,
  REAL: 8,
  LREAL: 0x30,
  USINT: 0x34,
  UINT: 0x35,
  UDINT: 0x36,
  SINT: 0x37,
  WCHAR: 0x3d,
};
const STRING_ROOT = 0x020a0000;
const WSTRING_ROOT = 0x020b0000;
const SOFT_NAMES = new Map(Object.entries(SOFT).map(([name, id]) => [ROOT + id, name]));

/** An associated value's blob (the simulator's side); TypeError for a type TIA does not allow as an associated value. */
export function associatedValueBlob(type: string, value: PlcValue, stringLength = 254): BlobValue {
  const t = type.toUpperCase();
  const data = Buffer.alloc(8);
  const n = typeof value === 'number' ? value : typeof value === 'boolean' ? Number(value) : typeof value === 'bigint' ? Number(value) : 0;
  const blob = (rootId: number, bytes: Buffer): BlobValue => ({ rootId, data: bytes, blobType: 2 });
  switch (t) {
    case 'BOOL':
    case 'BYTE':
    case 'USINT':
      data.writeUInt8(n & 0xff);
      return blob(ROOT + SOFT[t]!, data.subarray(0, 1));
    case 'SINT':
      data.writeInt8((n << 24) >> 24);
      return blob(ROOT + SOFT[t]!, data.subarray(0, 1));
    case 'CHAR':
      return blob(ROOT + SOFT[t]!, Buffer.from(String(value).slice(0, 1) || '\0', 'latin1'));
    case 'WORD':
    case 'UINT':
      data.writeUInt16BE(n & 0xffff);
      return blob(ROOT + SOFT[t]!, data.subarray(0, 2));
    case 'INT':
      data.writeInt16BE((n << 16) >> 16);
      return blob(ROOT + SOFT[t]!, data.subarray(0, 2));
    case 'DWORD':
    case 'UDINT':
      data.writeUInt32BE(n >>> 0);
      return blob(ROOT + SOFT[t]!, data.subarray(0, 4));
    case 'DINT':
      data.writeInt32BE(n | 0);
      return blob(ROOT + SOFT[t]!, data.subarray(0, 4));
    case 'REAL':
      data.writeFloatBE(n);
      return blob(ROOT + SOFT[t]!, data.subarray(0, 4));
    case 'LREAL':
      data.writeDoubleBE(n);
      return blob(ROOT + SOFT[t]!, data);
    case 'WCHAR': {
      const b = Buffer.alloc(2);
      b.writeUInt16BE(String(value).charCodeAt(0) || 0);
      return blob(ROOT + SOFT[t]!, b);
    }
    case 'STRING': {
      const max = Math.min(254, Math.max(1, stringLength));
      const text = Buffer.from(String(value), 'latin1').subarray(0, max);
      return blob(STRING_ROOT + max, Buffer.concat([Buffer.from([max, text.length]), text]));
    }
    case 'WSTRING': {
      const max = Math.min(0xfffe, Math.max(1, stringLength));
      const text = String(value).slice(0, max);
      const b = Buffer.alloc(4 + 2 * text.length);
      b.writeUInt16BE(max, 0);
      b.writeUInt16BE(text.length, 2);
      for (let i = 0; i < text.length; i++) b.writeUInt16BE(text.charCodeAt(i), 4 + 2 * i);
      return blob(WSTRING_ROOT + Math.min(max, 0xffff), b);
    }
    default:
      throw new TypeError(
        `an associated value of type ${type}: TIA allows BOOL, BYTE, CHAR, WORD, INT, DWORD, DINT, REAL, LREAL, USINT, UINT, UDINT, SINT, WCHAR, STRING, WSTRING`,
      );
  }
}

/** The associated values' array of a DAI: the type information, SD_1…SD_n, empty blobs to 17 elements. */
export function associatedValuesArray(values: readonly BlobValue[]): BlobValue[] {
  if (values.length > ASSOCIATED_VALUES.maxValues) throw new RangeError(`at most ${ASSOCIATED_VALUES.maxValues} associated values`);
  const out: BlobValue[] = [{ rootId: 3476, data: Buffer.alloc(ASSOCIATED_VALUES.typeInfoBytes), blobType: 2 }, ...values];
  while (out.length < ASSOCIATED_VALUES.count) out.push({ rootId: 0, data: Buffer.alloc(0) });
  return out;
}

/** An associated value's blob decoded by its root id; undefined for an empty element or a type not known. */
export function decodeAssociatedValue(b: BlobValue): AlarmValue | undefined {
  const v = b.data;
  if (v.length === 0) return undefined;
  if (b.rootId >= STRING_ROOT && b.rootId <= STRING_ROOT + 0xffff) {
    if (v.length < 2) return undefined;
    return { type: 'STRING', value: v.subarray(2, 2 + Math.min(v[1]!, v.length - 2)).toString('latin1') };
  }
  if (b.rootId >= WSTRING_ROOT && b.rootId <= WSTRING_ROOT + 0xffff) {
    if (v.length < 4) return undefined;
    const n = Math.min(v.readUInt16BE(2), (v.length - 4) >> 1);
    const chars: number[] = [];
    for (let i = 0; i < n; i++) chars.push(v.readUInt16BE(4 + 2 * i));
    return { type: 'WSTRING', value: String.fromCharCode(...chars) };
  }
  const type = SOFT_NAMES.get(b.rootId);
  if (!type) return undefined;
  const need: Record<string, number> = { WORD: 2, UINT: 2, INT: 2, WCHAR: 2, DWORD: 4, UDINT: 4, DINT: 4, REAL: 4, LREAL: 8 };
  if (v.length < (need[type] ?? 1)) return undefined;
  switch (type) {
    case 'BOOL':
      return { type, value: v[0] !== 0 };
    case 'CHAR':
      return { type, value: v.subarray(0, 1).toString('latin1') };
    case 'SINT':
      return { type, value: v.readInt8(0) };
    case 'WORD':
    case 'UINT':
      return { type, value: v.readUInt16BE(0) };
    case 'INT':
      return { type, value: v.readInt16BE(0) };
    case 'DWORD':
    case 'UDINT':
      return { type, value: v.readUInt32BE(0) };
    case 'DINT':
      return { type, value: v.readInt32BE(0) };
    case 'REAL':
      return { type, value: v.readFloatBE(0) };
    case 'LREAL':
      return { type, value: v.readDoubleBE(0) };
    case 'WCHAR':
      return { type, value: String.fromCharCode(v.readUInt16BE(0)) };
    default:
      return { type, value: v[0]! };
  }
}

const TOKEN = /@(\d+)(%[^@]+)@/g;
const SPEC = /^%([-+ 0#]*)(\d*)(?:\.(\d+))?([diuxXofeEgGsc])$/;

/** One value in a C printf conversion (`%d`, `%5.1f`, `%X`, `%s`); undefined when the conversion is not one of these. */
export function formatValue(spec: string, value: PlcValue): string | undefined {
  const m = SPEC.exec(spec);
  if (!m) return undefined;
  const [, flags = '', width = '', precision, conv] = m;
  const num =
    typeof value === 'boolean' ? Number(value) : typeof value === 'bigint' ? Number(value) : typeof value === 'number' ? value : Number.NaN;
  let s: string;
  switch (conv) {
    case 'd':
    case 'i':
    case 'u':
      if (Number.isNaN(num)) return undefined;
      s = Math.trunc(num).toString();
      break;
    case 'x':
    case 'X':
    case 'o':
      if (Number.isNaN(num)) return undefined;
      s = (Math.trunc(num) >>> 0).toString(conv === 'o' ? 8 : 16);
      if (conv === 'X') s = s.toUpperCase();
      break;
    case 'f':
    case 'e':
    case 'E':
    case 'g':
    case 'G': {
      if (Number.isNaN(num)) return undefined;
      const p = precision === undefined ? 6 : Number(precision);
      s = conv === 'f' ? num.toFixed(p) : conv === 'g' || conv === 'G' ? String(Number(num.toPrecision(p || 1))) : num.toExponential(p);
      if (conv === 'E' || conv === 'G') s = s.toUpperCase();
      break;
    }
    default:
      s = value instanceof Date ? value.toISOString() : String(value);
      if (conv === 'c') s = s.slice(0, 1);
      else if (precision !== undefined) s = s.slice(0, Number(precision));
  }
  if (flags.includes('+') && num >= 0 && 'dif'.includes(conv!)) s = `+${s}`;
  const w = Number(width || 0);
  if (s.length < w) s = flags.includes('-') ? s.padEnd(w) : flags.includes('0') && conv !== 's' ? s.padStart(w, '0') : s.padStart(w);
  return s;
}

/** `text` with each `@n%fmt@` replaced by SD_n (`values[n - 1]`); a placeholder without its value stays as written. */
export function fillPlaceholders(text: string, values: readonly (AlarmValue | undefined)[]): string {
  return text.replace(TOKEN, (whole, index: string, spec: string) => {
    const v = values[Number(index) - 1];
    if (!v) return whole;
    return formatValue(spec, v.value) ?? whole;
  });
}

/** Nanoseconds since 1970 as a Date; undefined for 0 (no time). */
function dateOfNs(ns: bigint | undefined): Date | undefined {
  return ns === undefined || ns === 0n ? undefined : new Date(Number(ns / 1_000_000n));
}

/** A Date as nanoseconds since 1970. */
export function nsOfDate(d: Date): bigint {
  return BigInt(d.getTime()) * 1_000_000n;
}

/** The alarm class that needs acknowledging: TIA's predefined class "Acknowledgement" is class 1 (an assumption; see docs/alarms.md). */
export const ACK_CLASS = 1;

/** A DAI as a PlcAlarm: values decoded, texts per language with the values in their placeholders (only `languages`' when given). */
export function toPlcAlarm(dai: Dai, languages?: readonly number[]): PlcAlarm {
  const decoded = dai.values.slice(1, 1 + ASSOCIATED_VALUES.maxValues).map(decodeAssociatedValue);
  let last = decoded.length;
  while (last > 0 && decoded[last - 1] === undefined) last--;
  const values = decoded.slice(0, last).map((v) => v ?? { type: 'NONE', value: '' });
  const needsAck = dai.hmi?.alarmClass === ACK_CLASS;
  const acked = dateOfNs(dai.ackTimestamp);
  const at = dateOfNs(dai.timestamp);
  const alarm: PlcAlarm = {
    id: Number(dai.cpuAlarmId),
    kind: 'Program_Alarm',
    state: dai.state,
    needsAck,
    acknowledged: !needsAck || acked !== undefined,
    values,
  };
  if (at) alarm[dai.state] = at;
  if (acked) alarm.acked = acked;
  if (dai.hmi) {
    alarm.priority = dai.hmi.priority;
    if (dai.hmi.alarmClass !== undefined) alarm.alarmClass = dai.hmi.alarmClass;
  }
  const byLanguage = new Map<number, Map<number, string>>();
  for (const [key, text] of dai.texts) {
    const lcid = key >>> 16;
    if (languages && languages.length > 0 && !languages.includes(lcid)) continue;
    let m = byLanguage.get(lcid);
    if (!m) byLanguage.set(lcid, (m = new Map<number, string>()));
    m.set(key & 0xffff, fillPlaceholders(text, decoded));
  }
  if (byLanguage.size > 0) {
    const texts: Record<string, AlarmTexts> = {};
    for (const [lcid, m] of byLanguage) {
      const t: AlarmTexts = { text: m.get(TextId.Alarm) ?? '' };
      const info = m.get(TextId.Info);
      if (info) t.info = info;
      const additional: string[] = [];
      for (let id = TextId.FirstAdditional; id <= TextId.LastAdditional; id++) additional.push(m.get(id) ?? '');
      while (additional.length > 0 && additional[additional.length - 1] === '') additional.pop();
      if (additional.length > 0) t.additional = additional;
      texts[languageOf(lcid)] = t;
    }
    alarm.texts = texts;
  }
  return alarm;
}
