'use strict';
const { attach, settleWithin, liveClient, warnDuplicateNames } = require('./shared/user');
const { tagTable, writeRequest, errorInfo, tagFailure } = require('..');

/**
 * plcwire-write: writes `msg.payload = { nameOrAddress: value }` (or
 * `msg.topic` + value) and sends the message on once the PLC acknowledged,
 * with `msg.results` per tag. Failures go to done(err) naming the tag.
 */
/** One error for a write refused as a whole, naming every tag of `names` ({ address: name }) with the library's words. */
function refusal(names, err) {
  // The library's refusal names the addresses already (lib/errors.ts writeRefusal); its cause has the words without them.
  const words = err && err.cause instanceof Error && err.cause.code === err.code ? err.cause : err;
  const failed = Object.entries(names).map(([address, name]) => ({ name, error: errorInfo(words, address) }));
  return failed.length > 0 ? Object.assign(tagFailure('write', failed), { cause: err }) : err;
}

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
        // Refused as a whole (not connected, the link lost, the queue full): the error names the tags as the flow
        // names them, as a failed tag's does; the library's error (it names the addresses) is the cause.
        .catch((err) => done(refusal(request.names, err)));
    });

    node.on('close', function (removed, done) {
      closing = true;
      settleWithin(connection ? connection.detach() : undefined).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-write', PlcwireWrite);
};
