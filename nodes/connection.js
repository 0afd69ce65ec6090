'use strict';
const { acquire, release, plc } = require('./shared/links');
const { settleWithin } = require('./shared/user');

/**
 * plcwire-connection (config): property `url`. Opens the shared link on its
 * first user, gives it back after the last; forwards link errors to the users'
 * Catch nodes through `this.users` (the runtime's convention for config nodes).
 */
/** The URL without a user:password@ part. */
function withoutCredentials(url) {
  return url.replace(/^([a-z0-9+.-]+:\/\/)[^/?#@]*@/i, '$1');
}

module.exports = function (RED) {
  function PlcwireConnection(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    node.name = config.name;
    node.url = String(config.url || '').trim();
    node.users = {};
    node.linkStatus = { state: 'connecting' };
    node.problem = undefined;
    let link;
    let lastError = '';

    Object.defineProperty(node, 'client', { get: () => link && link.client });

    function broadcast(status) {
      node.linkStatus = status;
      if (status.state === 'connected') lastError = '';
      for (const user of Object.values(node.users)) if (typeof user.onLinkStatus === 'function') user.onLinkStatus(status);
    }

    /** Reported once per distinct error between two connections, so a PLC that is off does not flood the log. */
    function reportError(err) {
      const text = err && err.message ? err.message : String(err);
      if (text === lastError) return;
      lastError = text;
      // Catch messages end up in debug sidebars and files: never with the URL's user info.
      const url = withoutCredentials(node.url);
      node.error(err, { topic: link ? link.name : url, payload: { url, state: node.linkStatus.state, code: err && err.code } });
    }

    const onStatus = (status) => broadcast(status);

    function open() {
      try {
        link = acquire(node.url, node);
      } catch (err) {
        // Each user reports this to its own Catch nodes once the flows have started (see problemReport).
        node.problem = err;
        broadcast({ state: 'invalid', error: err });
        return;
      }
      node.problem = undefined;
      link.on('status', onStatus);
      link.on('link-error', reportError);
      broadcast(link.status);
    }

    function shut() {
      const held = link;
      link = undefined;
      if (!held) return Promise.resolve();
      held.off('status', onStatus);
      held.off('link-error', reportError);
      return release(held, node);
    }

    /**
     * Why this connection cannot be opened, as the error its users report
     * (naming the connection, with the parser's code) and their Catch message.
     */
    node.problemReport = function () {
      const err = node.problem;
      if (!err) return undefined;
      const url = withoutCredentials(node.url);
      const error = new plc.PlcError(err.code || 'INVALID_URL', `connection "${node.name || url}": ${err.message}`);
      return { error, msg: { topic: node.name || url, payload: { url, state: 'invalid', code: error.code } } };
    };

    node.register = function (user) {
      node.users[user.id] = user;
      if (!link && !node.problem) open();
      else if (typeof user.onLinkStatus === 'function') user.onLinkStatus(node.linkStatus);
    };

    /** Resolves once the link is closed if `user` was the last one. */
    node.deregister = function (user) {
      delete node.users[user.id];
      if (Object.keys(node.users).length > 0) return Promise.resolve();
      node.problem = undefined;
      return shut();
    };

    node.on('close', function (removed, done) {
      node.users = {};
      settleWithin(shut()).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-connection', PlcwireConnection);

  const canRead = RED.auth.needsPermission('plcwire.read');

  /**
   * The address parser of a URL's protocol (the client's own, which knows the
   * URL's settings), or the S7 parser when no URL is given. `done()` frees it.
   * { error } when the URL itself is invalid.
   */
  function parserFor(url) {
    if (!url) return { parse: plc.parseAddress, done: () => undefined };
    try {
      const client = plc.createClient(String(url));
      return { parse: (a) => client.tag(a), done: () => client.close().catch(() => undefined) };
    } catch (err) {
      return { error: err };
    }
  }

  const urlAnswer = (err) => ({ ok: false, code: err.code, message: err.message });

  /**
   * Address validation for the editor with the library's own parser (the
   * driver of the URL's protocol): POST { url?, addresses: [...] } →
   * { results: { address: { ok, type, count } | { ok: false, code, message } } }.
   */
  RED.httpAdmin.post('/plcwire/validate', canRead, function (req, res) {
    const body = req.body || {};
    const addresses = Array.isArray(body.addresses) ? body.addresses.slice(0, 1000).map(String) : [];
    const parser = parserFor(body.url);
    if (parser.error) {
      res.json({ url: urlAnswer(parser.error), results: {} });
      return;
    }
    const results = {};
    for (const address of addresses) {
      try {
        const tag = parser.parse(address);
        results[address] = { ok: true, type: tag.type, count: tag.count };
      } catch (err) {
        results[address] = { ok: false, code: err.code || 'INVALID_ADDRESS', message: err.message };
      }
    }
    parser.done();
    res.json({ url: { ok: true }, results });
  });

  /**
   * CSV import for the tag table: POST { url?, text } → { url, tags: [{ name, address }],
   * problems: [{ line, code, name, address, message }] }, a type column checked
   * with the parser of the URL's protocol (the S7 parser when the URL is invalid).
   */
  RED.httpAdmin.post('/plcwire/csv', canRead, function (req, res) {
    const body = req.body || {};
    let parser = parserFor(body.url);
    const url = parser.error ? urlAnswer(parser.error) : { ok: true };
    if (parser.error) parser = parserFor(undefined);
    const { tags, problems } = plc.tagsFromCsv(String(body.text || ''), parser.parse);
    parser.done();
    res.json({ url, tags, problems });
  });

  /** URL ⇄ fields for the edit dialog, with the library's own parser and formatter. */
  RED.httpAdmin.post('/plcwire/url', canRead, function (req, res) {
    const body = req.body || {};
    try {
      if (body.endpoint) {
        const url = plc.formatUrl(body.endpoint);
        const endpoint = plc.parseUrl(url);
        res.json({ ok: true, url: plc.formatUrl(endpoint), endpoint, key: plc.endpointKey(endpoint) });
      } else {
        const endpoint = plc.parseUrl(String(body.url || ''));
        res.json({ ok: true, url: plc.formatUrl(endpoint), endpoint, key: plc.endpointKey(endpoint) });
      }
    } catch (err) {
      res.json({ ok: false, code: err.code, message: err.message });
    }
  });

  /**
   * The CPU presets of the dialog, from the library (lib/url.ts, S7_CPU_PRESETS):
   * { preset: { rack?, slot?, localTsap?, remoteTsap?, maxItems? } }, TSAPs as numbers.
   */
  RED.httpAdmin.get('/plcwire/presets', canRead, function (req, res) {
    res.json(plc.S7_CPU_PRESETS);
  });

  /** Serial ports for the freeport dialog. */
  RED.httpAdmin.get('/plcwire/serialports', canRead, function (req, res) {
    let SerialPort;
    try {
      ({ SerialPort } = require('serialport'));
    } catch {
      res.json([]);
      return;
    }
    SerialPort.list().then(
      (ports) => res.json(ports.map((p) => ({ path: p.path, manufacturer: p.manufacturer || '' }))),
      () => res.json([]),
    );
  });
};
