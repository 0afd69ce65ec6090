'use strict';
/**
 * One PLC client per endpoint (endpointKey of the URL), shared by every
 * connection config node that names it. Config nodes own links; user nodes
 * (read, write, heartbeat) reach them through their config node.
 */
const { EventEmitter } = require('node:events');
const plc = require('../..');

/** @type {Map<string, Link>} */
const links = new Map();

/** Parameters that change what a client may do to the PLC: two config nodes must agree on them to share a client. */
const SAFETY = ['readOnly', 'allow', 'control'];

class Link extends EventEmitter {
  /** `symbols`: { key, table?, strict } (see acquire). */
  constructor(key, url, endpoint, symbols) {
    super();
    this.key = key;
    this.url = url;
    this.endpoint = endpoint;
    this.symbolsKey = symbols.key;
    this.name = plc.endpointName(endpoint);
    this.owners = new Set();
    this.status = { state: 'connecting' };
    this.client = plc.createClient(endpoint, symbols.table ? { symbols: symbols.table, strictSymbols: !!symbols.strict } : {});
    this.client.on('state', (state) => {
      if (state !== 'reconnecting' && state !== 'idle') this.update({ state });
    });
    this.client.on('reconnecting', ({ delay, error }) => this.update({ state: 'reconnecting', delay, error }));
    // A listener on 'error' keeps an error event from ever throwing; errors reach users via 'status'.
    this.client.on('error', (error) => this.emit('link-error', error));
    // The layout check of the symbol table's DBs, on each connect (docs/symbols.md, "Stale layouts"): a block
    // whose length on the PLC is not its source's ({ block, db, declared, actual }, actual null: no such DB), or all fine.
    this.client.on('layoutMismatch', (event) => this.emit('layout-mismatch', event));
    this.client.on('layoutOk', (event) => this.emit('layout-ok', event));
    this.client.start();
  }

  update(status) {
    this.status = status;
    this.emit('status', status);
  }

  close() {
    if (links.get(this.key) === this) links.delete(this.key);
    return this.client.close().catch(() => undefined);
  }
}

function safetyOf(endpoint) {
  return JSON.stringify(SAFETY.map((k) => endpoint[k] ?? null));
}

/** The URL without a user:password@ part: conflict messages reach logs and Catch nodes. */
function withoutCredentials(url) {
  return String(url).replace(/^([a-z0-9+.-]+:\/\/)[^/?#@]*@/i, '$1');
}

/** A setting as a conflict message shows it. */
function shownSetting(value) {
  if (value === undefined || value === null) return 'not set';
  return Array.isArray(value) ? value.join(',') : String(value);
}

/** "control is true there, not set here; …": the write-safety settings of `here` that differ from `there`'s. */
function safetyDifferences(there, here) {
  return SAFETY.filter((k) => JSON.stringify(there[k] ?? null) !== JSON.stringify(here[k] ?? null))
    .map((k) => `${k} is ${shownSetting(there[k])} there, ${shownSetting(here[k])} here`)
    .join('; ');
}

/** Which way two connections' symbol sources differ (by their keys, '' for none). */
function sourcesDifference(there, here) {
  if (!here) return 'no symbol sources (it has some)';
  if (!there) return 'symbol sources (it has none)';
  return 'other symbol sources (or block numbers, or strictness)';
}

/** How a message names a connection node: its name and URL, or the URL alone. */
function connectionName(owner, url) {
  const name = owner && owner.name ? `"${owner.name}" ` : '';
  return `${name}(${withoutCredentials(url)})`;
}

/**
 * Takes (or opens) the link for `url` on behalf of `owner`, with the symbols
 * `{ key, table?, strict }` its client resolves names with (key: what they
 * were compiled from, '' for none). Throws PlcError INVALID_URL for a bad
 * URL; SETTINGS_CONFLICT when another config node already holds the link to
 * the same PLC with other write-safety settings (readOnly, allow, control) or
 * other symbol sources: one client has one set of them, so a node would
 * otherwise write (or resolve a name) under the other connection's rules.
 */
function acquire(url, owner, symbols = { key: '' }) {
  const endpoint = plc.parseUrl(url);
  const key = plc.endpointKey(endpoint);
  let link = links.get(key);
  const other = link && connectionName(link.owners.values().next().value, link.url);
  if (link && safetyOf(link.endpoint) !== safetyOf(endpoint)) {
    throw new plc.PlcError(
      'SETTINGS_CONFLICT',
      `${withoutCredentials(url)} is a valid URL, but it reaches the same PLC as connection ${other}, whose link is already open, with other settings (${safetyDifferences(link.endpoint, endpoint)}); connections to one PLC share one link: give both the same readOnly, allow and control, or use one connection node`,
    );
  }
  if (link && link.symbolsKey !== symbols.key) {
    throw new plc.PlcError(
      'SETTINGS_CONFLICT',
      `${withoutCredentials(url)} is a valid URL, but it reaches the same PLC as connection ${other}, whose link is already open, with ${sourcesDifference(link.symbolsKey, symbols.key)}; connections to one PLC share one link: give both the same sources, block numbers and strictness, or use one connection node`,
    );
  }
  if (!link) {
    link = new Link(key, url, endpoint, symbols);
    links.set(key, link);
  }
  link.owners.add(owner);
  return link;
}

/** Gives the link back; the last owner closes it. Always resolves. */
function release(link, owner) {
  link.owners.delete(owner);
  return link.owners.size === 0 ? link.close() : Promise.resolve();
}

/** For tests and diagnostics: how many links are open. */
function openLinks() {
  return links.size;
}

module.exports = { acquire, release, openLinks, plc };
