/**
 * The editor's check of a tag row on a connection that reads by name
 * (s7plus://, issue #31): a name is not an address, so the address parser
 * says nothing about it (the S7CommPlus client parses any well-formed name
 * to a placeholder tag, to be resolved at the read). Here it is looked up in
 * the connection's sources, else in the PLC's own browsed table: the PLC's
 * type, or INVALID_ADDRESS with the closest names; without either (the PLC
 * could not be browsed) the row says it was not checked and why, never a
 * type it does not know. No Node-RED.
 */
import { parseAddress } from '../address';
import { toPlcError } from '../errors';
import type { DriverTag } from '../link/driver';
import { addressOrSymbol, wholeBlock } from '../symbols/resolve';
import type { SymbolTable } from '../symbols';
import { resolveAddress, type AddressAnswer } from './symbol-config';

/** A parsed tag that stands for a name the client resolves at the read (lib/s7plus/client/names.ts NamedTag). */
const isNameTag = (tag: DriverTag): boolean => typeof (tag as { symbol?: unknown }).symbol === 'string';

/** A tag row's answer, with `unchecked` when the name could be looked up nowhere. */
export type NameAnswer = AddressAnswer | { ok: true; symbol: string; address: null; type: '?'; unchecked: string };

/** What the check needs: the URL's parser, the sources' table, and how to get the PLC's table (browse) when a name needs it. */
export interface NameCheck {
  parse: (address: string) => DriverTag & { type: string; count: number };
  table?: SymbolTable | undefined;
  /** The PLC's browsed table (the connection's own, or a browse made for the question); rejects when it cannot be had. */
  browse?: () => Promise<SymbolTable>;
}

/** `name` looked up in `table`: its entry's type and kind, or INVALID_ADDRESS with the closest names. */
export function nameInTable(name: string, table: SymbolTable): AddressAnswer {
  const entry = table.lookup(name) ?? wholeBlock(table, name);
  if (entry) return { ok: true, symbol: entry.name, address: entry.address, type: entry.type, kind: entry.kind };
  try {
    // The name is no address (the S7 syntax says why), so it goes the table's way: an unknown one gets its closest names.
    addressOrSymbol(name, parseAddress, table);
  } catch (err) {
    const e = toPlcError(err, 'INVALID_ADDRESS');
    return { ok: false, code: e.code, message: e.message };
  }
  return { ok: false, code: 'INVALID_ADDRESS', message: `unknown symbol ${name}` };
}

/**
 * Every address of a tag table answered as resolveAddress() does, except the
 * names the parser left for the PLC: those are looked up in the sources'
 * table when it has them, else in the PLC's browsed table (asked for at most
 * once, and only when such a name is there).
 */
export async function checkAddresses(addresses: readonly string[], check: NameCheck): Promise<Record<string, NameAnswer>> {
  const results: Record<string, NameAnswer> = {};
  const names: string[] = [];
  for (const address of addresses) {
    let named = false;
    try {
      named = isNameTag(check.parse(address));
    } catch {
      // Not parsed: resolveAddress gives the parser's (or the table's) answer.
    }
    if (named && !(check.table && check.table.lookup(address))) names.push(address);
    else if (named) results[address] = nameInTable(address, check.table!);
    else results[address] = resolveAddress(address, check.parse, check.table);
  }
  if (names.length === 0) return results;
  let browsed: SymbolTable | undefined;
  let why = 'the connection has no sources and cannot browse the PLC';
  if (check.browse) {
    try {
      browsed = await check.browse();
    } catch (err) {
      why = `the PLC could not be browsed: ${toPlcError(err).message}`;
    }
  }
  for (const name of names) {
    results[name] = browsed ? nameInTable(name, browsed) : { ok: true, symbol: name, address: null, type: '?', unchecked: why };
  }
  return results;
}
