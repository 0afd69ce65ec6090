'use strict';
/**
 * Tag tables and change detection for the read and write nodes: plain data in,
 * plain data out, no Node-RED and no sockets (tested on their own).
 */

/** Normalises a table of { name, address } (name defaults to the address; blank rows dropped). */
function tagTable(rows) {
  if (!Array.isArray(rows)) return [];
  const out = [];
  for (const row of rows) {
    if (!row) continue;
    const address = String(row.address ?? '').trim();
    if (!address) continue;
    const name = String(row.name ?? '').trim() || address;
    out.push({ name, address });
  }
  return out;
}

/**
 * The tags a message asks for with `msg.tags`: an address, an array of
 * addresses or of { name, address }, or an object { name: address }.
 * Returns undefined when the message names none.
 */
function tagsOfMessage(value) {
  if (value === undefined || value === null) return undefined;
  if (typeof value === 'string') return tagTable([{ address: value }]);
  if (Array.isArray(value)) return tagTable(value.map((v) => (typeof v === 'string' ? { address: v } : v)));
  if (typeof value === 'object') return tagTable(Object.entries(value).map(([name, address]) => ({ name, address })));
  return undefined;
}

/** An error as it travels on a message: plain data (Error objects do not survive cloning). */
function errorInfo(err, address) {
  return { code: (err && err.code) || 'PLC_ERROR', message: (err && err.message) || String(err), address };
}

/**
 * Turns readDetailed results into per-name outcomes, in table order:
 * [{ name, address, ok, value?, error? }].
 */
function outcomes(tags, results) {
  return tags.map(({ name, address }) => {
    const r = results[address];
    if (r && r.ok) return { name, address, ok: true, value: r.value };
    const error = r ? r.error : new Error(`no result for "${address}"`);
    return { name, address, ok: false, error: errorInfo(error, address) };
  });
}

function toNumber(v) {
  return typeof v === 'bigint' ? Number(v) : v;
}

/** True when two PLC values differ (numbers: by more than `deadband`). */
function changed(before, after, deadband) {
  if (typeof after === 'number' || typeof after === 'bigint') {
    if (typeof before !== 'number' && typeof before !== 'bigint') return true;
    if (typeof before === 'bigint' && typeof after === 'bigint' && !(deadband > 0)) return before !== after;
    const d = Math.abs(toNumber(after) - toNumber(before));
    return deadband > 0 ? d > deadband : d !== 0 || Number.isNaN(d);
  }
  if (after instanceof Date) return !(before instanceof Date) || before.getTime() !== after.getTime();
  if (Array.isArray(after)) {
    if (!Array.isArray(before) || before.length !== after.length) return true;
    return after.some((v, i) => changed(before[i], v, deadband));
  }
  return before !== after;
}

/**
 * Remembers the last value reported per tag name; `filter` keeps the outcomes
 * worth reporting: changed values (beyond the deadband) and changes of quality.
 */
class ChangeFilter {
  constructor(deadband = 0) {
    this.deadband = Number(deadband) > 0 ? Number(deadband) : 0;
    this.last = new Map();
  }

  filter(list) {
    const out = [];
    for (const o of list) {
      const prev = this.last.get(o.name);
      let report;
      if (!prev) report = true;
      else if (prev.ok !== o.ok) report = true;
      else if (!o.ok) report = prev.error.code !== o.error.code;
      else report = changed(prev.value, o.value, this.deadband);
      if (report) {
        this.last.set(o.name, o);
        out.push(o);
      }
    }
    return out;
  }

  clear() {
    this.last.clear();
  }
}

/**
 * Resolves a write request to { address: value } with the table's names:
 * `msg.payload = { nameOrAddress: value }`, or `msg.topic = nameOrAddress`
 * with the value as payload. Returns { values, names } or throws an Error
 * with code INVALID_VALUE.
 */
function writeRequest(table, msg) {
  const byName = new Map(table.map((t) => [t.name, t.address]));
  const payload = msg.payload;
  const entries = [];
  const topic = typeof msg.topic === 'string' ? msg.topic.trim() : '';
  if (isPlainObject(payload)) entries.push(...Object.entries(payload));
  else if (topic) entries.push([topic, payload]);
  else throw codeError('INVALID_VALUE', 'write needs msg.payload = { nameOrAddress: value } or msg.topic = address with a value');
  if (entries.length === 0) throw codeError('INVALID_VALUE', 'msg.payload names no tag to write');
  const values = {};
  const names = {};
  for (const [key, value] of entries) {
    if (value === undefined || value === null) throw codeError('INVALID_VALUE', `no value for "${key}"`, key);
    const address = byName.get(key) ?? key;
    if (Object.prototype.hasOwnProperty.call(values, address)) {
      throw codeError('INVALID_VALUE', `"${key}" and "${names[address]}" are the same address ${address}`, key);
    }
    values[address] = value;
    names[address] = key;
  }
  return { values, names };
}

function isPlainObject(v) {
  if (v === null || typeof v !== 'object' || Array.isArray(v) || Buffer.isBuffer(v) || v instanceof Date) return false;
  const proto = Object.getPrototypeOf(v);
  return proto === Object.prototype || proto === null;
}

function codeError(code, message, tag) {
  const err = new Error(message);
  err.code = code;
  if (tag !== undefined) err.tag = tag;
  return err;
}

module.exports = { tagTable, tagsOfMessage, outcomes, errorInfo, changed, ChangeFilter, writeRequest, codeError };
