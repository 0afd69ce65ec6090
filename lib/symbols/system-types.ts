/**
 * System data types TIA Portal writes unquoted in DB sources (`TCON_IP_v4`,
 * `HW_IO`, `IEC_TIMER` …): which names exist, and the layout of the ones
 * people keep in DBs with standard access whose members Siemens documents.
 * The layout engine looks a name up here only when no UDT of that name is
 * among the sources (a source's own UDT wins).
 *
 * Each layout is written in our own words from the facts of Siemens' help
 * and manuals; docs/symbols.md ("System types") names the source of each.
 * Members are laid out by the ordinary rules (layout.ts), so the sizes given
 * there are what the rules make of these members.
 */
import type { DataTypeName } from '../types';
import type { MemberDecl, SourcePosition, TypeDecl, TypeRef } from './model';

/**
 * Types that are a number under another name: hardware and connection
 * identifiers, block numbers, event and OB numbers. A member of such a type
 * is laid out and read as its base type.
 */
const ALIASES: Readonly<Record<string, DataTypeName>> = {
  // Hardware identifiers (the HW_ family): WORD.
  HW_ANY: 'WORD',
  HW_IO: 'WORD',
  HW_DEVICE: 'WORD',
  HW_DPMASTER: 'WORD',
  HW_DPSLAVE: 'WORD',
  HW_IOSYSTEM: 'WORD',
  HW_SUBMODULE: 'WORD',
  HW_MODULE: 'WORD',
  HW_INTERFACE: 'WORD',
  HW_IEPORT: 'WORD',
  HW_HSC: 'WORD',
  HW_PWM: 'WORD',
  HW_PTO: 'WORD',
  // Connection identifiers of open user communication: WORD; CONN_R_ID: DWORD.
  CONN_ANY: 'WORD',
  CONN_OUC: 'WORD',
  CONN_PRG: 'WORD',
  CONN_R_ID: 'DWORD',
  // Block, OB and event numbers.
  DB_ANY: 'UINT',
  DB_WWW: 'UINT',
  DB_DYN: 'UINT',
  OB_ANY: 'INT',
  OB_DELAY: 'INT',
  OB_TOD: 'INT',
  OB_CYCLIC: 'INT',
  OB_ATT: 'INT',
  OB_PCYCLE: 'INT',
  OB_HWINT: 'INT',
  OB_DIAG: 'INT',
  OB_TIMEERROR: 'INT',
  OB_STARTUP: 'INT',
  EVENT_ANY: 'DWORD',
  EVENT_ATT: 'DWORD',
  EVENT_HWINT: 'DWORD',
  PORT: 'UINT',
  RTM: 'UINT',
  PIP: 'UINT',
  AOM_IDENT: 'DWORD',
};

/** A member of a system structure: its name and type as TIA shows them. */
type Member = readonly [name: string, type: string];

/**
 * The data of an IEC timer (TP, TON, TOF; TIA names it IEC_TIMER or after the
 * instruction, TON_TIME …): start time, preset, elapsed time, then the
 * running, input and output bits in byte 12; 16 bytes with the reserve after
 * the bits (SYSTEM_BYTES).
 */
const IEC_TIMER_MEMBERS: readonly Member[] = [
  ['ST', 'Time'],
  ['PT', 'Time'],
  ['ET', 'Time'],
  ['RU', 'Bool'],
  ['IN', 'Bool'],
  ['Q', 'Bool'],
];

/**
 * System structures by name, their members in order. A type is an
 * elementary type (`Byte`, `UInt`), an alias above, another structure here,
 * or `Array[lo..hi] of T`.
 */
const STRUCTURES: Readonly<Record<string, readonly Member[]>> = {
  /** An IPv4 address: four bytes, most significant first. */
  IP_V4: [['ADDR', 'Array[1..4] of Byte']],
  /** Open user communication over TCP/UDP with an IPv4 partner (TSEND_C, TRCV_C, TCON): 14 bytes. */
  TCON_IP_V4: [
    ['InterfaceId', 'HW_ANY'],
    ['ID', 'CONN_OUC'],
    ['ConnectionType', 'Byte'],
    ['ActiveEstablished', 'Bool'],
    ['RemoteAddress', 'IP_V4'],
    ['RemotePort', 'UInt'],
    ['LocalPort', 'UInt'],
  ],
  /** The S7-1200's first connection description for TCON (block_length 64): 64 bytes. */
  TCON_PARAM: [
    ['block_length', 'UInt'],
    ['id', 'CONN_OUC'],
    ['connection_type', 'USInt'],
    ['active_est', 'Bool'],
    ['local_device_id', 'USInt'],
    ['local_tsap_id_len', 'USInt'],
    ['rem_subnet_id_len', 'USInt'],
    ['rem_staddr_len', 'USInt'],
    ['rem_tsap_id_len', 'USInt'],
    ['next_staddr_len', 'USInt'],
    ['local_tsap_id', 'Array[1..16] of Byte'],
    ['rem_subnet_id', 'Array[1..6] of USInt'],
    ['rem_staddr', 'Array[1..6] of USInt'],
    ['rem_tsap_id', 'Array[1..16] of Byte'],
    ['next_staddr', 'Array[1..6] of Byte'],
    ['spare', 'Word'],
  ],
  IEC_TIMER: IEC_TIMER_MEMBERS,
  TON_TIME: IEC_TIMER_MEMBERS,
  TOF_TIME: IEC_TIMER_MEMBERS,
  TP_TIME: IEC_TIMER_MEMBERS,
  /** The data of an IEC counter with INT values (CTU, CTD, CTUD on INT): six bits, a pad byte, PV and CV: 6 bytes. */
  IEC_COUNTER: [
    ['CU', 'Bool'],
    ['CD', 'Bool'],
    ['R', 'Bool'],
    ['LD', 'Bool'],
    ['QU', 'Bool'],
    ['QD', 'Bool'],
    ['PV', 'Int'],
    ['CV', 'Int'],
  ],
  /** The UDP partner's address for TUSEND/TURCV on the S7-1200: 8 bytes. */
  TADDR_PARAM: [
    ['REM_IP_ADDR', 'Array[1..4] of USInt'],
    ['REM_PORT_NR', 'UInt'],
    ['RESERVED', 'Word'],
  ],
};

/**
 * Structures that occupy more than their members: the CPU keeps a reserve
 * after them (an IEC timer's bits take byte 12; Siemens gives the whole as
 * 16 bytes). What the ordinary rules make of the members is extended to this.
 */
const SYSTEM_BYTES: Readonly<Record<string, number>> = { IEC_TIMER: 16, TON_TIME: 16, TOF_TIME: 16, TP_TIME: 16 };

/** The bytes a system structure occupies when more than its members take (IEC_TIMER: 16), or undefined. */
export function systemStructureBytes(decl: TypeDecl): number | undefined {
  return isSystemDecl(decl) ? SYSTEM_BYTES[decl.name.toUpperCase()] : undefined;
}

/**
 * Names TIA writes unquoted for system types and system function blocks
 * whose layout in a standard block is not in the table: no public source
 * gives their offsets (the LTIME timers, the counters of other widths,
 * TONR with its reset, the edge detectors). Refused by name.
 */
const WITHOUT_LAYOUT = new Set(
  [
    'IEC_LTIMER',
    'IEC_SCOUNTER',
    'IEC_DCOUNTER',
    'IEC_LCOUNTER',
    'IEC_UCOUNTER',
    'IEC_USCOUNTER',
    'IEC_UDCOUNTER',
    'IEC_ULCOUNTER',
    'TON',
    'TOF',
    'TP',
    'TONR',
    'TONR_TIME',
    'TON_LTIME',
    'TOF_LTIME',
    'TP_LTIME',
    'TONR_LTIME',
    'CTU',
    'CTD',
    'CTUD',
    'CTU_INT',
    'CTD_INT',
    'CTUD_INT',
    'CTU_DINT',
    'CTD_DINT',
    'CTUD_DINT',
    'R_TRIG',
    'F_TRIG',
    'ERROR_STRUCT',
    'TCON_IP_V6',
    'TCON_IP_RFC',
    'TCON_QDN',
    'LTOD',
    'LDT',
    'LTIME_OF_DAY',
    'DATE_AND_LTIME',
    'NREF',
    'CREF',
  ].map((s) => s.toUpperCase()),
);

/** Every system type name TIA writes unquoted that the parser accepts as a type (any case). */
export function isSystemTypeName(name: string): boolean {
  const key = name.toUpperCase();
  return key in ALIASES || key in STRUCTURES || WITHOUT_LAYOUT.has(key);
}

/** The names whose layout is known, as TIA spells them, for messages. */
export const KNOWN_LAYOUTS: readonly string[] = [
  'TCON_IP_v4',
  'TCON_Param',
  'TADDR_Param',
  'IP_V4',
  'IEC_TIMER',
  'TON_TIME',
  'TOF_TIME',
  'TP_TIME',
  'IEC_COUNTER',
  'HW_ANY, HW_IO … (WORD)',
  'CONN_OUC …',
];

/** The base type of an alias (`HW_IO` → WORD), or undefined. */
export function systemAlias(name: string): DataTypeName | undefined {
  return ALIASES[name.toUpperCase()];
}

const built = new Map<string, TypeDecl>();
const systemDecls = new WeakSet<TypeDecl>();

/** True for the declaration of a system structure (TIA writes its name unquoted). */
export function isSystemDecl(decl: TypeDecl): boolean {
  return systemDecls.has(decl);
}

/** The declaration of a system structure by name (any case), built once, or undefined. */
export function systemStructure(name: string): TypeDecl | undefined {
  const key = name.toUpperCase();
  const members = STRUCTURES[key];
  if (!members) return undefined;
  let decl = built.get(key);
  if (!decl) {
    const at: SourcePosition = Object.freeze({ file: `system type ${key}`, line: 0, column: 0 });
    decl = Object.freeze({
      kind: 'type',
      name: SPELLING[key] ?? key,
      attributes: {},
      body: { kind: 'struct', members: members.map(([n, t]) => member(n, t, at)), at },
      at,
    } satisfies TypeDecl);
    built.set(key, decl);
    systemDecls.add(decl);
  }
  return decl;
}

/** How TIA spells the structures' names. */
const SPELLING: Readonly<Record<string, string>> = {
  IP_V4: 'IP_V4',
  TCON_IP_V4: 'TCON_IP_v4',
  TCON_PARAM: 'TCON_Param',
  TADDR_PARAM: 'TADDR_Param',
  IEC_TIMER: 'IEC_TIMER',
  IEC_COUNTER: 'IEC_COUNTER',
  TON_TIME: 'TON_TIME',
  TOF_TIME: 'TOF_TIME',
  TP_TIME: 'TP_TIME',
};

const ELEMENTARY: Readonly<Record<string, DataTypeName>> = {
  BOOL: 'BOOL',
  BYTE: 'BYTE',
  WORD: 'WORD',
  USINT: 'USINT',
  UINT: 'UINT',
  INT: 'INT',
  TIME: 'TIME',
};

function member(name: string, type: string, at: SourcePosition): MemberDecl {
  return { name, type: typeOf(type, at), attributes: {}, comment: '', at };
}

function typeOf(text: string, at: SourcePosition): TypeRef {
  const array = /^Array\[(\d+)\.\.(\d+)\] of (\w+)$/.exec(text);
  if (array) return { kind: 'array', dims: [{ low: Number(array[1]), high: Number(array[2]) }], element: typeOf(array[3]!, at), at };
  const elementary = ELEMENTARY[text.toUpperCase()];
  if (elementary) return { kind: 'elementary', type: elementary, stringLength: 0, at };
  return { kind: 'named', name: text, at };
}
