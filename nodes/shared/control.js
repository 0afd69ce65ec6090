'use strict';
/**
 * The control node's plain logic: which action a message asks for, results
 * as plain data (ISO strings instead of Dates: messages are cloned and
 * shown in debug sidebars), and which diagnostic entries are new since the
 * last call. No Node-RED and no sockets.
 */
const { PlcError } = require('../..');

const ACTIONS = Object.freeze(['info', 'state', 'diagnostics', 'clock', 'clock-sync', 'blocks', 'stop', 'start']);
/** Actions that change the PLC: refused on a connection without `control=true`. */
const CONTROL_ACTIONS = Object.freeze(['stop', 'start', 'clock-sync']);

/**
 * The action of a message: `msg.action` if it is set (an unknown one is an
 * INVALID_VALUE error: it was meant as an action), else `msg.topic` if it
 * names an action (topics often carry other things), else `configured`.
 */
function actionOf(msg, configured) {
  const asked = msg.action;
  if (asked !== undefined && asked !== null && asked !== '') {
    if (ACTIONS.includes(asked)) return asked;
    throw new PlcError('INVALID_VALUE', `msg.action "${String(asked)}" is not one of ${ACTIONS.join(', ')}`);
  }
  if (typeof msg.topic === 'string' && ACTIONS.includes(msg.topic)) return msg.topic;
  return configured;
}

/** A Date as an ISO string; null for a time stamp that is no date (a CPU clock never set). */
function isoOrNull(date) {
  return date instanceof Date && !Number.isNaN(date.getTime()) ? date.toISOString() : null;
}

/** A diagnostic entry with its time as an ISO string. */
function plainEntry(e) {
  return { ...e, time: isoOrNull(e.time) };
}

/** cpuState() as the node sends it: `state` in lower case ('run', 'stop' …), the CPU's mode as read, the transition's time as ISO. */
function plainState(s) {
  return {
    state: String(s.mode).toLowerCase(),
    mode: s.mode,
    modeCode: s.modeCode,
    previousCode: s.previousCode,
    eventId: s.eventId,
    time: isoOrNull(s.time),
  };
}

function keyOf(e) {
  return [e.time instanceof Date ? e.time.getTime() : NaN, e.eventId, e.priority, e.ob, e.dataId, e.info1, e.info2, e.info3].join('/');
}

/**
 * Remembers the newest diagnostic entry reported; `take(entries)` (newest
 * first, as the CPU gives them) returns the ones logged since. The first
 * call returns every entry (none was reported yet). When the remembered
 * entry has left the buffer (more new entries than it holds, or a memory
 * reset), the entries later than its time stamp are the new ones.
 */
class DiagnosticsCursor {
  constructor() {
    this.last = undefined;
  }

  take(entries) {
    let fresh = entries;
    if (this.last) {
      const i = entries.findIndex((e) => keyOf(e) === this.last.key);
      fresh = i >= 0 ? entries.slice(0, i) : entries.filter((e) => e.time instanceof Date && e.time.getTime() > this.last.time);
    }
    if (entries.length > 0) this.last = { key: keyOf(entries[0]), time: entries[0].time instanceof Date ? entries[0].time.getTime() : NaN };
    return fresh;
  }
}

module.exports = { ACTIONS, CONTROL_ACTIONS, actionOf, isoOrNull, plainEntry, plainState, DiagnosticsCursor };
