'use strict';
const { attach, settleWithin, noConnectionError, warnDuplicateNames } = require('./shared/user');
const { tagTable, tagsOfMessage, outcomes, tagFailure, ChangeFilter, PlcError } = require('..');
const { tagErrorsStatus } = require('./shared/status');

/** Reads waiting behind the running one at most; more is an error, not memory growth. */
const MAX_WAITING_READS = 100;

/** Each address once, in table order (a table may name one address twice). */
function uniqueAddresses(list) {
  return [...new Set(list.map((t) => t.address))];
}

/**
 * plcwire-read: polls `tags` every `interval` ms (0 = only on input) and
 * reads on every input message (`msg.tags` reads other addresses on demand).
 * Reads run one at a time: a poll never overlaps the previous one.
 */
module.exports = function (RED) {
  function PlcwireRead(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const tags = tagTable(config.tags);
    warnDuplicateNames(RED, node, tags);
    const interval = Math.max(0, Number(config.interval) || 0);
    const output = ['object', 'per-tag', 'changes'].includes(config.output) ? config.output : 'object';
    const changes = new ChangeFilter(config.deadband);
    let timer;
    let closing = false;
    let chain = Promise.resolve();
    let waiting = 0;
    let failing = false;
    /** Names of tags whose failure was already reported to Catch (reported again only after they recover). */
    const reported = new Set();

    const connection = attach(RED, node, config.connection, (status) => {
      if (status.state === 'connected') {
        if (interval > 0) schedule(0);
        return !failing;
      }
      return true;
    });

    /** Runs reads one after another. */
    function serial(job) {
      if (waiting >= MAX_WAITING_READS) {
        return Promise.reject(new PlcError('QUEUE_FULL', `more than ${MAX_WAITING_READS} reads waiting; the PLC answers slower than messages arrive`));
      }
      waiting++;
      const run = chain.then(() => {
        waiting--;
        return job();
      });
      chain = run.catch(() => undefined);
      return run;
    }

    // The configured table's addresses, made once: the client recognises an
    // address array it has seen (its parsed tags, plan and request frames are
    // kept for it), so every poll passes the same array.
    const tableAddresses = uniqueAddresses(tags);

    async function read(list) {
      if (!connection) throw noConnectionError(RED);
      if (connection.problem) throw connection.problem;
      const client = connection.client;
      if (!client) throw noConnectionError(RED);
      const results = await client.readDetailed(list === tags ? tableAddresses : uniqueAddresses(list));
      return outcomes(list, results);
    }

    function showQuality(list) {
      const bad = list.filter((o) => !o.ok).length;
      failing = bad > 0;
      if (failing) node.status(tagErrorsStatus(RED._, bad));
      else if (connection) connection.showLink();
    }

    /** Messages for `list` in the node's output mode, built on `base` (the input message, if any). */
    function messages(list, base, mode) {
      if (mode === 'object') {
        const msg = base || {};
        msg.payload = {};
        msg.quality = {};
        msg.addresses = {};
        for (const o of list) {
          msg.quality[o.name] = o.ok ? 'good' : 'bad';
          msg.addresses[o.name] = o.address;
          if (o.ok) msg.payload[o.name] = o.value;
        }
        const bad = list.filter((o) => !o.ok);
        if (bad.length > 0) msg.errors = Object.fromEntries(bad.map((o) => [o.name, o.error]));
        else delete msg.errors;
        if (!base) msg.topic = node.name || 'plcwire';
        return [msg];
      }
      return list.map((o, i) => {
        const msg = base ? (i === list.length - 1 ? base : RED.util.cloneMessage(base)) : {};
        msg.topic = o.name;
        msg.address = o.address;
        msg.payload = o.ok ? o.value : null;
        msg.quality = o.ok ? 'good' : 'bad';
        if (o.ok) delete msg.errors;
        else msg.errors = { [o.name]: o.error };
        return msg;
      });
    }

    function emit(send, list, base, mode) {
      const out = mode === 'changes' ? changes.filter(list) : list;
      const msgs = messages(out, base, mode === 'changes' ? 'per-tag' : mode);
      if (msgs.length === 1) send(msgs[0]);
      else if (msgs.length > 1) send([msgs]);
    }

    function schedule(delay) {
      clearTimeout(timer);
      timer = undefined;
      if (closing || interval <= 0) return;
      timer = setTimeout(poll, delay);
    }

    function poll() {
      timer = undefined;
      if (closing || !connection || node.linkState !== 'connected' || tags.length === 0) return;
      const started = Date.now();
      serial(() => read(tags)).then(
        (list) => {
          if (closing) return;
          showQuality(list);
          emit((m) => node.send(m), list, undefined, output);
          const bad = list.filter((o) => !o.ok && !reported.has(o.name));
          for (const o of list) if (o.ok) reported.delete(o.name);
          if (bad.length > 0) {
            bad.forEach((o) => reported.add(o.name));
            node.error(tagFailure('read', bad), { topic: node.name || 'plcwire', payload: Object.fromEntries(bad.map((o) => [o.name, o.error])) });
          }
        },
        (err) => {
          // A lost link shows on the status and reaches Catch through the connection; anything else is reported here.
          if (!closing && err.code !== 'NOT_CONNECTED' && err.code !== 'CONNECTION_LOST' && err.code !== 'CLOSED') {
            node.error(err, { topic: node.name || 'plcwire', payload: {} });
          }
        },
      ).finally(() => {
        if (!closing && node.linkState === 'connected') schedule(Math.max(0, interval - (Date.now() - started)));
      });
    }

    node.on('input', function (msg, send, done) {
      const asked = tagsOfMessage(msg.tags);
      const list = asked || tags;
      if (list.length === 0) {
        done(new PlcError('INVALID_ADDRESS', RED._('plcwire.errors.noTags')));
        return;
      }
      serial(() => read(list)).then(
        (results) => {
          // On-demand addresses have no history to compare with: 'changes' sends them one per tag.
          const mode = asked && output === 'changes' ? 'per-tag' : output;
          if (!asked) showQuality(results);
          emit(send, results, msg, mode);
          const bad = results.filter((o) => !o.ok);
          done(bad.length > 0 ? tagFailure('read', bad) : undefined);
        },
        (err) => done(err),
      );
    });

    node.on('close', function (removed, done) {
      closing = true;
      clearTimeout(timer);
      timer = undefined;
      settleWithin(connection ? connection.detach() : undefined).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-read', PlcwireRead);
};
