'use strict';
/**
 * Every node status the nodes show, translated here with the runtime's `RED._`
 * (numbers filled in), so the editor, Status nodes and dashboards built on
 * them all receive the same words, never an i18n key. Every text stays under
 * 20 characters in every locale.
 */

/** @typedef {(key: string, params?: object) => string} Translate  RED._ of the node's module */

const { retryReason } = require('../../dist/lib/flows/outage');

/** The status text of each RetryReason (lib/flows/outage.ts). */
const RETRY_REASON_KEYS = {
  'not-trusted': 'plcwire.status.notTrusted',
  expired: 'plcwire.status.certificateExpired',
  'not-yet-valid': 'plcwire.status.certificateNotYetValid',
  password: 'plcwire.status.passwordRefused',
};

/**
 * The link state: connecting, connected, retry in N s (or why, when waiting will not help: the certificate is
 * not trusted or out of its dates, the password was refused), closed, bad connection
 * (settings conflict: another connection node holds the PLC's link with other settings),
 * no connection. Connected with a notice of the connection (tags by name):
 * a data block whose length differs from its source's (`DB1 20≠24`: the
 * sources' length, then the PLC's), or sources that did not compile.
 */
function linkStatus(t, status) {
  switch (status.state) {
    case 'connected':
      if (status.notice && status.notice.kind === 'layout') return layoutStatus(t, status.notice);
      if (status.notice && status.notice.kind === 'sources') return { fill: 'yellow', shape: 'dot', text: t('plcwire.status.sourceError') };
      return { fill: 'green', shape: 'dot', text: t('plcwire.status.connected') };
    case 'connecting':
      return { fill: 'yellow', shape: 'ring', text: t('plcwire.status.connecting') };
    case 'reconnecting': {
      // A retry that waiting alone will not help says why instead (issue #31); the Catch message has the whole text.
      const reason = RETRY_REASON_KEYS[retryReason(status.error)];
      if (reason) return { fill: 'red', shape: 'ring', text: t(reason) };
      return { fill: 'red', shape: 'ring', text: t('plcwire.status.retryIn', { s: Math.max(1, Math.round((status.delay ?? 0) / 1000)) }) };
    }
    case 'closed':
      return { fill: 'grey', shape: 'ring', text: t('plcwire.status.closed') };
    case 'invalid':
      // A valid URL another connection node to the same PLC disagrees with: not a bad connection of its own.
      if (status.error && status.error.code === 'SETTINGS_CONFLICT')
        return { fill: 'red', shape: 'dot', text: t('plcwire.status.settingsConflict') };
      return { fill: 'red', shape: 'dot', text: t('plcwire.status.badConfig') };
    case 'unconfigured':
    default:
      return { fill: 'red', shape: 'ring', text: t('plcwire.status.noConnection') };
  }
}

/** A data block's length on the PLC (`actual`; null: the PLC has no such DB) is not what its source declares (`declared`). */
function layoutStatus(t, { db, declared, actual }) {
  if (actual === null) return { fill: 'red', shape: 'ring', text: t('plcwire.status.layoutMissing', { db }) };
  return { fill: 'red', shape: 'ring', text: t('plcwire.status.layoutMismatch', { db, declared, actual }) };
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
function waitingStatus(t) {
  return { fill: 'yellow', shape: 'ring', text: t('plcwire.status.waiting') };
}

/** Control: the CPU's operating mode (RUN, STOP, STARTUP, HOLD, DEFECT, UNKNOWN), as the CPU names it in every language. */
function cpuStatus(t, mode) {
  const m = mode || 'UNKNOWN';
  const fill = m === 'RUN' ? 'green' : m === 'STOP' || m === 'DEFECT' ? 'red' : m === 'UNKNOWN' ? 'grey' : 'yellow';
  return { fill, shape: 'dot', text: t('plcwire-control.status.cpu', { mode: m }) };
}

/** Control: `n` diagnostic entries read (`onlyNew`: new since the last call). */
function entriesStatus(t, n, onlyNew) {
  return { fill: 'green', shape: 'dot', text: t(onlyNew ? 'plcwire-control.status.newEntries' : 'plcwire-control.status.entries', { n }) };
}

/** Control: `action` failed (the error, with its code, went to Catch). */
function failedStatus(t, action) {
  return { fill: 'red', shape: 'ring', text: t('plcwire-control.status.failed', { action }) };
}

/**
 * Alarms: none active (green ring); active, all acknowledged (yellow dot, `3 active`); some waiting for an
 * operator (red dot, `1/3 unacked`: one of three).
 */
function alarmCountsStatus(t, { active, unacknowledged }) {
  if (active === 0) return { fill: 'green', shape: 'ring', text: t('plcwire-alarms.status.none') };
  if (unacknowledged === 0) return { fill: 'yellow', shape: 'dot', text: t('plcwire-alarms.status.active', { active }) };
  return { fill: 'red', shape: 'dot', text: t('plcwire-alarms.status.unacknowledged', { active, unacknowledged }) };
}

/** Alarms: the subscription failed or was lost (the error went to Catch, once per outage). */
function alarmsFailedStatus(t) {
  return { fill: 'red', shape: 'ring', text: t('plcwire-alarms.status.failed') };
}

module.exports = {
  linkStatus,
  layoutStatus,
  tagErrorsStatus,
  sentStatus,
  aliveStatus,
  lostStatus,
  waitingStatus,
  cpuStatus,
  entriesStatus,
  failedStatus,
  alarmCountsStatus,
  alarmsFailedStatus,
};
