'use strict';
/**
 * Node status from the real link state. Texts are i18n keys of the node's
 * catalog (the editor translates them); the one with a number is translated
 * here. Every text stays under 20 characters in every locale.
 */

/** @param {(key: string, params?: object) => string} t  RED._ of the node's module */
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

module.exports = { linkStatus };
