/**
 * TSAPs of an S7 connection, in one place: a rack/slot CPU is called at
 * (connection type << 8) | (rack << 5 | slot), its caller names itself by the
 * connection type alone (connection type PG 1, OP 2, basic/S7 3). CPUs
 * addressed by configured TSAPs (S7-200's CP 243-1, LOGO!) take the URL's
 * localTsap/remoteTsap instead (lib/url.ts, S7_CPU_PRESETS).
 */

const CONNECTION_TYPES = Object.freeze({ pg: 1, op: 2, basic: 3 });

export type ConnectionTypeName = keyof typeof CONNECTION_TYPES;

/** The called (remote) TSAP of a rack/slot CPU. */
export function remoteTsapFor(type: ConnectionTypeName, rack: number, slot: number): number {
  return (CONNECTION_TYPES[type] << 8) | ((rack & 0x07) << 5) | (slot & 0x1f);
}

/** The calling (local) TSAP a client sends to a rack/slot CPU. */
export function localTsapFor(type: ConnectionTypeName): number {
  return CONNECTION_TYPES[type] << 8;
}

/** The rack and slot a called TSAP names, or undefined when it is not of the rack/slot form (a configured TSAP). */
export function rackSlotOf(calledTsap: number): { rack: number; slot: number } | undefined {
  const type = calledTsap >> 8;
  if (type < 1 || type > 3) return undefined;
  return { rack: (calledTsap >> 5) & 0x07, slot: calledTsap & 0x1f };
}
