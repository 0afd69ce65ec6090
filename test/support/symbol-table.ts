/**
 * SymbolTables by hand, per lib/symbols/model.ts, for client tests that
 * must not depend on the source parser and the layout engine: members are
 * given with their offsets, as a layout would place them in standard
 * access; the entries, their addresses and children are derived.
 */
import type { BlockSummary, SymbolEntry, SymbolTable } from '../../lib/symbols/model';
import type { DataTypeName } from '../../lib/types';
import { elementByteLength } from '../../lib/values';

export type Member =
  | { name: string; type: DataTypeName; byte: number; bit?: number; count?: number; stringLength?: number }
  | { name: string; struct: Member[]; byte: number; size: number; count?: undefined }
  | { name: string; structArray: Member[]; byte: number; size: number; count: number };

export interface Block {
  name: string;
  db: number;
  length: number;
  members: Member[];
}

function width(size: number): string {
  return size === 2 ? 'DBW' : size === 4 ? 'DBD' : 'DBB';
}

function addressOf(db: number, type: DataTypeName, byte: number, bit: number, count: number | undefined, stringLength: number): string {
  if (type === 'BOOL') return `DB${db}.DBX${byte}.${bit}${count === undefined ? '' : `:BOOL[${count}]`}`;
  const spec = type === 'STRING' || type === 'WSTRING' ? `${type}[${stringLength}]` : type;
  if (count !== undefined) return `DB${db}.DBB${byte}:${spec}[${count}]`;
  return `DB${db}.${width(elementByteLength(type, stringLength))}${byte}:${spec}`;
}

const fold = (name: string) => name.replace(/"/g, '').toLowerCase();

/** Levenshtein distance, for suggestions. */
function distance(a: string, b: string): number {
  const row = Array.from({ length: b.length + 1 }, (_, j) => j);
  for (let i = 1; i <= a.length; i++) {
    let prev = row[0]!;
    row[0] = i;
    for (let j = 1; j <= b.length; j++) {
      const cur = row[j]!;
      row[j] = Math.min(row[j]! + 1, row[j - 1]! + 1, prev + (a[i - 1] === b[j - 1] ? 0 : 1));
      prev = cur;
    }
  }
  return row[b.length]!;
}

/** A table of the given blocks: lookup by name with or without quotes, any case; suggestions within 3 edits. */
export function symbolTable(blocks: Block[]): SymbolTable {
  const entries: SymbolEntry[] = [];
  const common = { comment: '', area: 'DB' as const };
  const add = (prefix: string, db: number, m: Member): string => {
    const name = `${prefix}.${m.name}`;
    if ('type' in m) {
      const stringLength = m.stringLength ?? 0;
      const bit = m.bit ?? 0;
      const size = m.type === 'BOOL' ? Math.ceil((bit + (m.count ?? 1)) / 8) : elementByteLength(m.type, stringLength) * (m.count ?? 1);
      entries.push({
        ...common,
        name,
        type: m.count === undefined ? m.type : `Array[0..${m.count - 1}] of ${m.type}`,
        kind: m.count === undefined ? 'elementary' : 'array',
        dataType: m.type,
        stringLength,
        db,
        byte: m.byte,
        bit: m.type === 'BOOL' ? bit : null,
        size,
        address: addressOf(db, m.type, m.byte, bit, m.count, stringLength),
      });
      return name;
    }
    const at = entries.length;
    const struct: SymbolEntry = {
      ...common,
      name,
      type: 'struct' in m ? 'Struct' : `Array[0..${m.count - 1}] of Struct`,
      kind: 'struct' in m ? 'struct' : 'array',
      stringLength: 0,
      db,
      byte: m.byte,
      bit: null,
      size: 'struct' in m ? m.size : m.size * m.count,
      address: `DB${db}.DBB${m.byte}:BYTE[${'struct' in m ? m.size : m.size * m.count}]`,
    };
    entries.push(struct);
    let children: string[];
    if ('struct' in m) {
      children = m.struct.map((c) => add(name, db, c));
    } else {
      children = [];
      for (let i = 0; i < m.count; i++) {
        const shifted = m.structArray.map((c) => ({ ...c, byte: c.byte + i * m.size }));
        const element = { name: '', struct: shifted, byte: m.byte + i * m.size, size: m.size };
        const elementName = `${name}[${i}]`;
        const e = entries.length;
        add('', db, element);
        // add() named it ".": rename the element and its members under `name[i]`.
        for (let k = e; k < entries.length; k++) {
          const old = entries[k]!;
          const renamed = elementName + old.name.slice(1);
          entries[k] = { ...old, name: renamed, ...(old.children ? { children: old.children.map((c) => elementName + c.slice(1)) } : {}) };
        }
        children.push(elementName);
      }
    }
    entries[at] = { ...struct, children };
    return name;
  };
  for (const b of blocks) {
    const top = entries.length;
    const name = `"${b.name}"`;
    entries.push({
      ...common,
      name,
      type: 'Struct',
      kind: 'struct',
      stringLength: 0,
      db: b.db,
      byte: 0,
      bit: null,
      size: b.length,
      address: `DB${b.db}.DBB0:BYTE[${b.length}]`,
    });
    const children = b.members.map((m) => add(name, b.db, m));
    entries[top] = { ...entries[top]!, children };
  }
  const byName = new Map(entries.map((e) => [fold(e.name), e]));
  const summaries: BlockSummary[] = blocks.map((b) => ({ name: b.name, db: b.db, length: b.length, file: `${b.name}.db` }));
  return {
    entries,
    blocks: summaries,
    types: [],
    lookup: (name) => byName.get(fold(name)),
    suggest: (name, max = 3) =>
      entries
        .map((e) => ({ e, d: distance(fold(name), fold(e.name)) }))
        .filter((x) => x.d <= 3)
        .sort((a, b) => a.d - b.d)
        .slice(0, max)
        .map((x) => x.e.name),
  };
}
