'use strict';
const { attach, settleWithin, liveClient, warnDuplicateNames } = require('./shared/user');
const { tagTable, writeRequest, errorInfo, tagFailure } = require('..');

/**
 * plcwire-write: writes `msg.payload = { nameOrAddress: value }` (or
 * `msg.topic` + value) and sends the message on once the PLC acknowledged,
 * with `msg.results` per tag. Failures go to done(err) naming the tag.
 */
module.exports = function (RED) {
  function PlcwireWrite(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const table = tagTable(config.tags);
    warnDuplicateNames(RED, node, table);
    let closing = false;

    const connection = attach(RED, node, config.connection);

    node.on('input', function (msg, send, done) {
      let client;
      let request;
      try {
        client = liveClient(RED, connection);
        request = writeRequest(table, msg);
      } catch (err) {
        done(err);
        return;
      }
      client
        .writeDetailed(request.values)
        .then((results) => {
          if (closing) return done();
          msg.results = {};
          const failed = [];
          for (const [address, name] of Object.entries(request.names)) {
            const r = results[address];
            if (r && r.ok) msg.results[name] = { ok: true, address };
            else {
              const info = errorInfo(r ? r.error : undefined, address);
              msg.results[name] = { ok: false, ...info };
              failed.push({ name, error: info });
            }
          }
          if (failed.length < Object.keys(request.names).length) send(msg);
          done(failed.length > 0 ? tagFailure('write', failed) : undefined);
        })
        .catch((err) => done(err));
    });

    node.on('close', function (removed, done) {
      closing = true;
      settleWithin(connection ? connection.detach() : undefined).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-write', PlcwireWrite);
};
