'use strict';
const plc = require('..');
const { ClientPool, withoutCredentials } = require('../dist/lib/flows/client-pool');
const { settleWithin } = require('./shared/user');
const symbols = require('../dist/lib/flows/symbol-config');
const s7plusAdmin = require('./shared/s7plus-admin');
const { testConnection } = require('../dist/lib/doctor/request');
const editor = require('../dist/lib/flows/editor-answers');
const { PlcTables } = require('../dist/lib/flows/plc-tables');
const { OutageReports } = require('../dist/lib/flows/outage');

/** One client per PLC, shared by every connection node that names it (and agrees on its settings). */
const pool = new ClientPool();
/** The PLCs' browsed tables the editor's name checks use (s7plus://), kept a few seconds per PLC. */
const plcTables = new PlcTables();

/**
 * plcwire-connection (config): properties `url`, and for tags by name
 * `symbolSources` [{ name, content, encoding? }], `dbNumbers` [{ block, db }]
 * and `strictSymbols`. Compiles the sources when it starts (a failed compile
 * is reported and leaves absolute addresses working), opens the shared link on
 * its first user, gives it back after the last; forwards link errors to the
 * users' Catch nodes through `this.users` (the runtime's convention for config
 * nodes).
 */
module.exports = function (RED) {
  function PlcwireConnection(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    node.name = config.name;
    node.url = String(config.url || '').trim();
    /** Every node that uses this connection, by id: they hear the link's status and keep the link open. */
    let registered = {};
    /**
     * What the runtime forwards this node's error() and status() through: one user per flow (tab or subflow
     * instance). The runtime hands an error to the Catch nodes of each user's flow, so two users on one tab (a
     * read and a write node) would make a Catch node hear every link error twice (issue #26).
     */
    node.users = {};
    const forwardVia = () => {
      const byFlow = new Map();
      for (const user of Object.values(registered)) if (!byFlow.has(user.z)) byFlow.set(user.z, user);
      node.users = Object.fromEntries([...byFlow.values()].map((u) => [u.id, u]));
    };
    node.problem = undefined;
    const compiled = symbols.compile(config);
    /** The compiled symbol table, or undefined (no sources, or they did not compile). */
    node.symbols = compiled.table;
    /** Why the sources did not compile: [{ code, message, file?, line?, column? }]. */
    node.symbolProblems = compiled.problems || [];
    // The PLC's password (s7plus://) is a credential: in no flow export, no property a Debug node could show.
    const password = node.credentials && node.credentials.password ? node.credentials.password : undefined;
    const symbolsOf = { key: symbols.symbolsKey(config), table: node.symbols, strict: !!config.strictSymbols, password };
    /** Data blocks whose length on the PLC differs from their source's, by DB number, since the link came up. */
    const mismatches = new Map();
    let link;
    /** One Catch message per outage, until the link has stayed up (lib/flows/outage.ts). */
    const outage = new OutageReports(() => node.linkStatus.state === 'connected');

    Object.defineProperty(node, 'client', { get: () => link && link.client });

    /**
     * The link's status as the users show it, read when asked: the state is the
     * client's supervisor's (LinkSupervisor.state, lib/link/supervisor.ts, the
     * one source of a link's state, through the pooled link's status), never a
     * copy kept here; 'invalid' when the link could not be opened.
     */
    Object.defineProperty(node, 'linkStatus', { enumerable: true, get: () => shown(current()) });

    /** The link's own status: invalid (node.problem), the pooled link's, or connecting before it is opened. */
    function current() {
      if (node.problem) return { state: 'invalid', error: node.problem };
      return link ? link.status : { state: 'connecting' };
    }

    /** The link's status with what the users show instead of "connected": a layout mismatch, or sources that did not compile. */
    function shown(status) {
      if (status.state !== 'connected') return status;
      const mismatch = mismatches.values().next().value;
      if (mismatch) return { ...status, notice: { kind: 'layout', db: mismatch.db, declared: mismatch.declared, actual: mismatch.actual } };
      if (node.symbolProblems.length > 0) return { ...status, notice: { kind: 'sources' } };
      return status;
    }

    /** Tells every user the link's status (after it or what it shows changed). */
    function broadcast() {
      const status = node.linkStatus;
      outage.state(status.state);
      for (const user of Object.values(registered)) if (typeof user.onLinkStatus === 'function') user.onLinkStatus(status);
    }

    function onMismatch(event) {
      const known = mismatches.get(event.db);
      if (known && known.declared === event.declared && known.actual === event.actual) return;
      mismatches.set(event.db, event);
      const key = event.actual === null ? 'plcwire-connection.errors.layoutMissing' : 'plcwire-connection.errors.layoutMismatch';
      node.warn(RED._(key, { block: event.block, db: event.db, declared: event.declared, actual: event.actual }));
      broadcast();
    }

    function onLayoutOk() {
      if (mismatches.size === 0) return;
      mismatches.clear();
      broadcast();
    }

    if (node.symbolProblems.length > 0) {
      // Once the flows have started, so the users' Catch nodes hear it too (the log has it either way).
      const problems = node.symbolProblems;
      const report = () => {
        const more = problems.length > 1 ? RED._('plcwire-connection.errors.more', { n: problems.length - 1 }) : '';
        const text =
          RED._('plcwire-connection.errors.sources', { name: node.name || withoutCredentials(node.url), problem: problems[0].message }) +
          more;
        node.error(new plc.PlcError(problems[0].code || 'INVALID_SOURCE', text), {
          topic: node.name || withoutCredentials(node.url),
          payload: { problems },
        });
      };
      RED.events.once('flows:started', report);
      node.on('close', () => RED.events.removeListener('flows:started', report));
    }

    /** The first error of an outage goes to Catch, once; the ones after it only to the status (lib/flows/outage.ts, issue #26). */
    function reportError(err) {
      if (!outage.first()) return;
      // Catch messages end up in debug sidebars and files: never with the URL's user info. The whole text is in the
      // payload too (a Debug node shows the payload): a refused certificate's message holds the fingerprint= to pin.
      const url = withoutCredentials(node.url);
      const payload = { url, state: node.linkStatus.state, code: err && err.code, message: err && err.message ? err.message : String(err) };
      node.error(err, { topic: link ? link.name : url, payload });
    }

    const onStatus = (status) => {
      // A mismatch is the PLC's answer on one connection: the client checks again on the next.
      if (status.state !== 'connected') mismatches.clear();
      broadcast();
    };

    function open() {
      try {
        link = pool.acquire(node.url, node, symbolsOf);
      } catch (err) {
        // Each user reports this to its own Catch nodes once the flows have started (see problemReport).
        node.problem = err;
        broadcast();
        return;
      }
      node.problem = undefined;
      link.on('status', onStatus);
      link.on('link-error', reportError);
      link.on('layout-mismatch', onMismatch);
      link.on('layout-ok', onLayoutOk);
      broadcast();
    }

    function shut() {
      const held = link;
      link = undefined;
      if (!held) return Promise.resolve();
      held.off('status', onStatus);
      held.off('link-error', reportError);
      held.off('layout-mismatch', onMismatch);
      held.off('layout-ok', onLayoutOk);
      return pool.release(held, node);
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
      registered[user.id] = user;
      forwardVia();
      if (!link && !node.problem) open();
      else if (typeof user.onLinkStatus === 'function') user.onLinkStatus(node.linkStatus);
    };

    /** Resolves once the link is closed if `user` was the last one. */
    node.deregister = function (user) {
      delete registered[user.id];
      forwardVia();
      if (Object.keys(registered).length > 0) return Promise.resolve();
      node.problem = undefined;
      return shut();
    };

    node.on('close', function (removed, done) {
      outage.close();
      registered = {};
      node.users = {};
      settleWithin(shut()).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-connection', PlcwireConnection, { credentials: { password: { type: 'password' } } });

  const canRead = RED.auth.needsPermission('plcwire.read');
  s7plusAdmin(RED, canRead);

  /**
   * The editor's questions, answered by the library (lib/flows/editor-answers.ts):
   * POST plcwire/validate { url?, addresses, symbolSources?, dbNumbers?, id?, password? } → { url, symbols, results }:
   *   each address with the URL's own parser and the sources; a name an s7plus:// connection reads by name against
   *   the sources, else the PLC's browsed table (the deployed connection's client, or a browse kept a few seconds;
   *   the password typed or the node's credential): the PLC's type, invalid with the closest names, or `unchecked`.
   * POST plcwire/csv { url?, text } → { url, tags, problems }; POST plcwire/csv/export { tags } → { csv };
   * POST plcwire/duplicates { tags } → { duplicates: [{ name, rows }] };
   * POST plcwire/url { url } | { endpoint } → { ok, url, endpoint, key, fields, placeholders }; { fields, kept? } → the URL the
   *   connection dialog's fields make, or the parser's message and the field it is about; { preset } → a CPU preset's fields
   *   (lib/flows/url-fields.ts); GET plcwire/presets → the CPU presets.
   */
  RED.httpAdmin.post('/plcwire/validate', canRead, function (req, res) {
    const body = req.body || {};
    const browse = (url) => {
      const link = pool.linkOf(url);
      const password = link ? undefined : s7plusAdmin.passwordOf(RED, body);
      return plcTables.tableOf(url, { live: link && link.client, ...(password !== undefined ? { password } : {}) });
    };
    editor.validateAnswer(body, browse).then((answer) => {
      if (!res.writableEnded) res.json(answer);
    });
  });

  /**
   * The connection dialog's compile of its sources, and the tag tables'
   * completion: POST { symbolSources, dbNumbers } → { blocks: [{ name, db,
   * length, file, instanceOf? }], entries: [{ name, address, type, kind,
   * children? }], types, errors: [{ code, message, file?, line?, column? }] },
   * compiled with the library's compileSymbols().
   */
  RED.httpAdmin.post('/plcwire/symbols', canRead, function (req, res) {
    res.json(symbols.describe(symbols.compileCached(editor.symbolConfig(req.body || {}))));
  });

  RED.httpAdmin.post('/plcwire/csv', canRead, (req, res) => res.json(editor.csvImportAnswer(req.body || {})));
  RED.httpAdmin.post('/plcwire/csv/export', canRead, (req, res) => res.json(editor.csvExportAnswer(req.body || {})));
  RED.httpAdmin.post('/plcwire/duplicates', canRead, (req, res) => res.json(editor.duplicatesAnswer(req.body || {})));
  RED.httpAdmin.post('/plcwire/url', canRead, (req, res) => res.json(editor.urlAnswer(req.body || {})));
  RED.httpAdmin.get('/plcwire/presets', canRead, (req, res) => res.json(plc.S7_CPU_PRESETS));

  /**
   * Test connection: POST { url, addresses?, timeout?, symbolSources?,
   * dbNumbers?, strictSymbols?, id?, password? } → the library's connection doctor, { ok,
   * steps: [{ step, ok, detail, hint? }] } (lib/doctor/request.ts: names
   * resolve through the dialog's sources as the connection's reads will, a
   * `symbols` step names the file and line when they do not compile). It
   * never outlives its request: when the editor closes it (dialog closed, page
   * left), the walk is aborted and closes every socket it opened. The password
   * typed in the dialog or the node's credential (by id) goes to a driver that
   * takes one; no answer carries it.
   */
  RED.httpAdmin.post('/plcwire/doctor', canRead, function (req, res) {
    const body = req.body || {};
    const stop = new AbortController();
    const onClose = () => {
      if (!res.writableEnded) stop.abort();
    };
    res.on('close', onClose);
    testConnection({
      body,
      // The dialog's sources as it holds them (not yet deployed ones too), compiled as the connection node compiles them at start.
      compiled: symbols.compileCached(editor.symbolConfig(body)),
      password: () => s7plusAdmin.passwordOf(RED, body),
      signal: stop.signal,
      words: {
        sources: (problem) => RED._('plcwire-connection.doctor.sources', { problem }),
        more: (n) => RED._('plcwire-connection.errors.more', { n }),
        namesNotChecked: (names) => RED._('plcwire-connection.doctor.namesNotChecked', { names }),
        sourcesHint: RED._('plcwire-connection.doctor.sourcesHint'),
      },
    }).then((answer) => {
      res.off('close', onClose);
      if (!stop.signal.aborted && !res.writableEnded) res.json(answer);
    });
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
