'use strict';
const { attach, settleWithin, liveClient } = require('./shared/user');
const plc = require('..');
const { cpuStatus, entriesStatus, failedStatus } = require('./shared/status');
const { configuredAction, actionOf, DiagnosticsCursor, plainEntry, plainState, isoOrNull } = require('../dist/lib/flows/control');

/**
 * plcwire-control: the S7 system services on input: identity (`info`), CPU
 * state, diagnostic buffer (optionally only the entries new since the last
 * call), clock read and sync, block counts, and stop/start (only on a
 * connection with `control=true`, which the client enforces before anything
 * is sent). `msg.topic` or `msg.action` naming an action overrides the
 * configured one. The result goes out in `msg.payload`, the action in
 * `msg.topic`; failures go to done(err) with the library's code.
 */
module.exports = function (RED) {
  function PlcwireControl(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const configured = configuredAction(config.action);
    const newOnly = config.newOnly === true || config.newOnly === 'true';
    const cursor = new DiagnosticsCursor();
    let closing = false;

    const connection = attach(RED, node, config.connection);

    /** Runs `action` on the S7 client; resolves the payload (plain data: ISO strings, no Date objects). */
    async function run(action, client) {
      switch (action) {
        case 'info': {
          const info = await client.info();
          node.status(cpuStatus(RED._, info.state));
          return { ...info, clock: isoOrNull(info.clock) };
        }
        case 'state': {
          const state = plainState(await client.cpuState());
          node.status(cpuStatus(RED._, state.mode));
          return state;
        }
        case 'diagnostics': {
          const entries = await client.diagnosticBuffer();
          const chosen = newOnly ? cursor.take(entries) : entries;
          node.status(entriesStatus(RED._, chosen.length, newOnly));
          return chosen.map(plainEntry);
        }
        case 'clock':
          return isoOrNull(await client.readClock());
        case 'clock-sync': {
          const now = new Date();
          await client.setClock(now);
          return { set: now.toISOString() };
        }
        case 'blocks':
          return { ...(await client.listBlocks()) };
        case 'stop':
        case 'start': {
          if (action === 'stop') await client.stop();
          else await client.hotStart();
          const state = plainState(await client.cpuState());
          node.status(cpuStatus(RED._, state.mode));
          return { state: state.state };
        }
      }
      throw new plc.PlcError('INVALID_VALUE', `unknown action "${action}"`);
    }

    node.on('input', function (msg, send, done) {
      let action;
      let client;
      try {
        action = actionOf(msg, configured);
        client = liveClient(RED, connection);
        if (!(client instanceof plc.S7Client)) {
          throw new plc.PlcError(
            'NOT_SUPPORTED',
            RED._('plcwire-control.errors.notS7', { action, protocol: client.endpoint ? client.endpoint.protocol : '?' }),
          );
        }
      } catch (err) {
        if (action) msg.topic = action;
        done(err);
        return;
      }
      run(action, client)
        .then((payload) => {
          if (closing) return done();
          msg.topic = action;
          msg.payload = payload;
          send(msg);
          done();
        })
        .catch((err) => {
          if (closing) return done();
          node.status(failedStatus(RED._, action));
          msg.topic = action;
          done(err);
        });
    });

    node.on('close', function (removed, done) {
      closing = true;
      settleWithin(connection ? connection.detach() : undefined).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-control', PlcwireControl);
};
