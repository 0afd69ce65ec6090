'use strict';
/**
 * Every node status the nodes show. A text without a number is an i18n key of
 * the node's catalog (the editor translates it); a text with a number is
 * translated here with the runtime's `RED._`. Every text stays under 20
 * characters in every locale.
 */

/** @typedef {(key: string, params?: object) => string} Translate  RED._ of the node's module */

/** The link state: connecting, connected, retry in N s, closed, bad connection, no connection. */
function linkStatus(t, status) {
  switch (status.state) {
    case 'connected':
      return { fill: 'green', shape: 'dot', text: 'plcwire.status.connected' };
    case 'connecting':
      return { fill: 'yellow', shape: 'ring', text: 'plcwire.status.connecting' };
    case 'reconnecting':
      return { fill: 'red', shape: 'ring', text: t('plcwire.status.retryIn', { s: Math.max(1, Math.round((status.delay ?? 0) / 1000)) }) };
    case 'closed':
      return { fill: 'grey', shape: 'ring', text: 'plcwire.status.closed' };
    case 'invalid':
      return { fill: 'red', shape: 'dot', text: 'plcwire.status.badConfig' };
    case 'unconfigured':
    default:
      return { fill: 'red', shape: 'ring', text: 'plcwire.status.noConnection' };
  }
}

/** Read node: the link is up but `n` tags of the last read failed. */
function tagErrorsStatus(t, n) {
  return { fill: 'yellow', shape: 'dot', text: t('plcwire.status.tagErrors', { n }) };
}

/** Heartbeat without a watched address: `n` life signs written. */
function sentStatus(t, n) {
  return { fill: 'green', shape: 'dot', text: t('plcwire.status.sent', { n }) };
}

/** Heartbeat: the PLC's life sign has changed `n` times. */
function aliveStatus(t, n) {
  return { fill: 'green', shape: 'dot', text: t('plcwire.status.alive', { n }) };
}

/** Heartbeat: the PLC's life sign has not changed for `ms` milliseconds. */
function lostStatus(t, ms) {
  return { fill: 'red', shape: 'dot', text: t('plcwire.status.lost', { s: Math.round(ms / 1000) }) };
}

/** Heartbeat: connected, waiting for the PLC's life sign to change the first time. */
function waitingStatus() {
  return { fill: 'yellow', shape: 'ring', text: 'plcwire.status.waiting' };
}

module.exports = { linkStatus, tagErrorsStatus, sentStatus, aliveStatus, lostStatus, waitingStatus };
