'use strict';
/** What the read, write and heartbeat nodes share: attaching to a connection and settling close in time. */
const { linkStatus } = require('./status');
const plc = require('../..');

/** Close handlers must call done within a few seconds whatever happens (the runtime gives up at 15 s). */
const CLOSE_DEADLINE_MS = 2000;

/** Resolves when `promise` settles or after `ms`, whichever is first; leaves no timer behind. */
function settleWithin(promise, ms = CLOSE_DEADLINE_MS) {
  let timer;
  const deadline = new Promise((resolve) => (timer = setTimeout(resolve, ms)));
  return Promise.race([Promise.resolve(promise).catch(() => undefined), deadline]).finally(() => clearTimeout(timer));
}

/**
 * Registers `node` as a user of its connection config node. `onStatus` hears
 * every link status (also the current one, at once). Returns the attachment,
 * or undefined when no connection is configured (the node's status says so).
 */
function attach(RED, node, connectionId, onStatus) {
  const config = connectionId ? RED.nodes.getNode(connectionId) : null;
  const show = (status) => node.status(linkStatus(RED._, status));
  if (!config || typeof config.register !== 'function') {
    show({ state: 'unconfigured' });
    return undefined;
  }
  // The link's state, read from the connection when asked: it is the client's supervisor's
  // (LinkSupervisor.state, lib/link/supervisor.ts, the one source of it), never a copy kept here.
  Object.defineProperty(node, 'linkState', { configurable: true, enumerable: true, get: () => config.linkStatus.state });
  node.onLinkStatus = (status) => {
    if (!onStatus || onStatus(status) !== false) show(status);
  };
  config.register(node);
  const problem = typeof config.problemReport === 'function' ? config.problemReport() : undefined;
  if (problem) {
    whenStarted(RED, node, () => {
      node.onLinkStatus(config.linkStatus);
      node.error(problem.error, problem.msg);
    });
  }
  return {
    config,
    /** The shared client, or undefined when the connection could not be opened. */
    get client() {
      return config.client;
    },
    /** The connection's compiled symbol table, or undefined (no sources, or they did not compile). */
    get symbols() {
      return config.symbols;
    },
    /** Why requests cannot be made (bad URL, no link), as an Error with a code, or undefined. */
    get problem() {
      return config.problem;
    },
    showLink: () => show(config.linkStatus),
    detach: () => config.deregister(node),
  };
}

/**
 * Runs `report` once the flows have started. While they start, the runtime
 * has not yet collected a tab's Catch and Status nodes (it does so after
 * creating all of its nodes): an error or status of a node being created
 * reaches none of them.
 */
function whenStarted(RED, node, report) {
  RED.events.once('flows:started', report);
  node.on('close', () => RED.events.removeListener('flows:started', report));
}

/**
 * Warns about every tag name the table gives to more than one row: in object
 * output only one of their values could arrive, and a write by name reaches one of them.
 */
function warnDuplicateNames(RED, node, table) {
  for (const { name, rows } of plc.duplicateNames(table)) {
    node.warn(RED._('plcwire.errors.duplicateName', { name, rows: rows.map((i) => i + 1).join(', ') }));
  }
}

/** The error a node reports when no connection node is configured. */
function noConnectionError(RED) {
  const err = new Error(RED._('plcwire.errors.noConnection'));
  err.code = 'NOT_CONNECTED';
  return err;
}

/**
 * The client of a node's connection (the attachment attach() returned), ready
 * for a request, or the error the node reports instead: NOT_CONNECTED when no
 * connection is configured or its link is closed, the connection's own
 * problem (a bad URL, a settings conflict) when it could not be opened.
 */
function liveClient(RED, connection) {
  if (!connection) throw noConnectionError(RED);
  if (connection.problem) throw connection.problem;
  const client = connection.client;
  if (!client) throw noConnectionError(RED);
  return client;
}

module.exports = { attach, settleWithin, liveClient, warnDuplicateNames, CLOSE_DEADLINE_MS };
