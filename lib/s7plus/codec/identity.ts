/**
 * The CPU's identity over S7CommPlus: the device ("PAOM") string a PLC puts
 * into the ServerSessionVersion struct (314) of its CreateObject answer,
 * member 319 (SessionVersionSystemPaomString), a WString of three fields:
 *
 *     <paom id>;<order code>[ ];<firmware>        "1;6ES7 215-1AG40-0XB0 ;V4.2"
 *
 * The firmware is the major.minor a CPU's legitimation depends on (V or S,
 * PLCSIM Advanced writes "S4.1"); the order code may end in a space. Source:
 * s7commplus (MIT), legitimation.py (`extract_session_version_string`,
 * `_parse_paom_string`, their examples "1;6ES7 512-1CK01-0AB0;V2.9" and
 * "1;6ES7 SIM-01500-APLC;S4.1"), connection.py
 * (`_strip_paom_string_in_session_version`: "1;6ES7 215-1BG40-0XB0 ;V4.2"),
 * server.py (`_build_server_session_version_struct`). Pure.
 */
import { DataType, Ids } from '../constants';
import type { PValue, StructValue } from './pvalue';

/** What the device string says: the order code (MLFB) and the firmware version, as the PLC wrote them. */
export interface DeviceIdentity {
  /** The whole string as it came: "1;6ES7 516-3AN02-0AB0 ;V3.1". */
  device: string;
  /** "6ES7 516-3AN02-0AB0"; undefined when the string has no second field. */
  orderCode: string | undefined;
  /** "V3.1" (major.minor: what the PLC tells here); undefined when the last field is not a version. */
  firmware: string | undefined;
}

/** A device string longer than this is not one (a hostile PLC's): it is ignored. */
const MAX_DEVICE_STRING = 256;
const FIRMWARE = /^[VS]\d{1,3}(\.\d{1,4}){1,2}$/i;

function isStruct(v: unknown): v is Extract<StructValue, { members: unknown }> {
  return typeof v === 'object' && v !== null && Array.isArray((v as { members?: unknown }).members);
}

/** The device string of a ServerSessionVersion value; undefined when it carries none (older firmware, the s7commplus emulator's V1). */
export function deviceString(version: PValue | undefined): string | undefined {
  if (version?.type !== DataType.Struct || !isStruct(version.value)) return undefined;
  const member = version.value.members.find((m) => m.key === Ids.SessionVersionSystemPaomString);
  const text = member?.value.type === DataType.WString ? member.value.value : undefined;
  return typeof text === 'string' && text.length > 0 && text.length <= MAX_DEVICE_STRING ? text : undefined;
}

/** The order code and firmware of a device string; fields that are not there stay undefined. */
export function parseDeviceString(device: string): DeviceIdentity {
  const fields = device.split(';');
  const order = fields.length >= 3 ? fields[1]!.trim() : undefined;
  const last = fields.length >= 3 ? fields.at(-1)!.trim() : undefined;
  return {
    device,
    orderCode: order === '' ? undefined : order,
    firmware: last !== undefined && FIRMWARE.test(last) ? last.toUpperCase() : undefined,
  };
}

/**
 * The device string a CPU with this order code and firmware sends: the
 * firmware cut to major.minor ("V3.1.0" → "V3.1"), since clients read only
 * those two numbers (legitimation.py `_FIRMWARE` matches the whole field).
 */
export function formatDeviceString(orderCode: string, firmware: string): string {
  const majorMinor = /^([VS]?)(\d+)\.(\d+)/i.exec(firmware);
  const version = majorMinor ? `${majorMinor[1] || 'V'}${majorMinor[2]}.${majorMinor[3]}` : firmware;
  return `1;${orderCode} ;${version}`;
}
