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

/**
 * Takes (or opens) the link for `url` on behalf of `owner`, with the symbols
 * `{ key, table?, strict }` its client resolves names with (key: what they
 * were compiled from, '' for none). Throws PlcError INVALID_URL for a bad
 * URL, or when another config node shares the endpoint with different
 * write-safety settings (read-only, allow-list); INVALID_SOURCE when it
 * shares it with other symbol sources (one client has one symbol table: a
 * name would otherwise mean what the first connection node's sources say).
 */
function acquire(url, owner, symbols = { key: '' }) {
  const endpoint = plc.parseUrl(url);
  const key = plc.endpointKey(endpoint);
  let link = links.get(key);
  if (link && safetyOf(link.endpoint) !== safetyOf(endpoint)) {
    throw new plc.PlcError(
      'INVALID_URL',
      `${url} reaches the same PLC as ${link.url} but with other readOnly/allow/control settings; give both connections the same ones`,
    );
  }
  if (link && link.symbolsKey !== symbols.key) {
    throw new plc.PlcError(
      'INVALID_SOURCE',
      `${url} reaches the same PLC as ${link.url} but with other symbol sources; give both connections the same sources, block numbers and strictness`,
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
