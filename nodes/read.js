'use strict';
const { attach, settleWithin, liveClient, warnDuplicateNames } = require('./shared/user');
const { tagTable, tagsOfMessage, outcomes, tagFailure, ChangeFilter, PolledTable, PlcError, isLinkError } = require('..');
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
 *
 * A read of the configured table in which every tag succeeded (the common
 * case) takes a short way: the client's values by address, turned into the
 * message by builders made once for the table (PolledTable), with no
 * per-tag outcome objects. Any failed tag takes the long way, through
 * per-tag outcomes. Both send the same messages. Every message sent is a
 * fresh object, one send() each: nothing a downstream node changes in one
 * message shows in another, and Node-RED clones none of them (it clones
 * every message after the first of one send([msgs]) call). The messages of
 * one read share one _msgid, as those of one send([msgs]) call do.
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
    const topic = node.name || 'plcwire';
    let timer;
    let closing = false;
    let chain = Promise.resolve();
    let waiting = 0;
    let failing = false;
    /** What the node's status shows: 'link' (the connection's state) or 'tags' (how many failed). */
    let shown;
    /** Names of tags whose failure was already reported to Catch (reported again only after they recover). */
    const reported = new Set();

    const connection = attach(RED, node, config.connection, (status) => {
      const show = status.state !== 'connected' || !failing;
      if (status.state === 'connected' && interval > 0) schedule(0);
      if (show) shown = 'link';
      return show;
    });

    /** Runs reads one after another. */
    function serial(job) {
      if (waiting >= MAX_WAITING_READS) {
        return Promise.reject(
          new PlcError('QUEUE_FULL', `more than ${MAX_WAITING_READS} reads waiting; the PLC answers slower than messages arrive`),
        );
      }
      waiting++;
      const run = chain.then(() => {
        waiting--;
        return job();
      });
      chain = run.catch(() => undefined);
      return run;
    }

    // The configured table, made ready once: the client recognises the address
    // array it has seen (its parsed tags, plan and request frames are kept for
    // it), so every read of the table passes the same array.
    const table = new PolledTable(tags);

    /**
     * Reads the table: { values } by address when every tag succeeded,
     * else { list } of per-tag outcomes. A failure of the whole read rejects.
     */
    async function readTable() {
      const client = liveClient(RED, connection);
      try {
        return { values: await client.read(table.addresses) };
      } catch (err) {
        if (err && err.code === 'TAG_ERRORS' && err.results) return { list: outcomes(tags, err.results) };
        throw err;
      }
    }

    async function readList(list) {
      const results = await liveClient(RED, connection).readDetailed(uniqueAddresses(list));
      return { list: outcomes(list, results) };
    }

    /**
     * Shows how many tags failed, on every read that had failures (a Status
     * node deployed later sees it at the next poll); else the link's state,
     * only when it is not shown already (it would be sent on to every Status
     * node at every poll).
     */
    function showQuality(bad) {
      failing = bad > 0;
      if (failing) {
        shown = 'tags';
        node.status(tagErrorsStatus(RED._, bad));
      } else if (shown !== 'link' && connection) {
        shown = 'link';
        connection.showLink();
      }
    }

    /** Messages for the outcomes `list` in `mode` ('object' or 'per-tag'), built on `base` (the input message, if any). */
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
        if (!base) msg.topic = topic;
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

    /** Sends the outcomes of a read of `list` in `mode` (for the table: 'changes' sends what changed). */
    function emit(send, list, base, mode) {
      const out = mode === 'changes' ? changes.filter(list) : list;
      const msgs = messages(out, base, mode === 'changes' ? 'per-tag' : mode);
      const id = base || msgs.length < 2 ? undefined : RED.util.generateId();
      for (const msg of msgs) {
        if (id) msg._msgid = id;
        send(msg);
      }
    }

    /** A per-tag message of row `i` of the table, which read `value` (`id`: the poll's message id, without `base`). */
    function rowMessage(i, value, base, id) {
      const t = tags[i];
      let msg;
      if (base) {
        msg = base;
        msg.topic = t.name;
        msg.address = t.address;
        msg.payload = value;
        msg.quality = 'good';
        delete msg.errors;
      } else msg = { topic: t.name, address: t.address, payload: value, quality: 'good', _msgid: id };
      // Two rows of one address read one value: the later row's message gets its own copy.
      return table.repeated[i] ? RED.util.cloneMessage(msg) : msg;
    }

    /** Sends a read of the whole table in which every tag succeeded (`values` by address) in `mode`. */
    function emitGood(send, values, base, mode) {
      if (mode === 'object') {
        const payload = table.payload(values);
        const quality = table.goodQuality();
        const addresses = table.addressesByName();
        if (!base) {
          send({ payload, quality, addresses, topic });
          return;
        }
        base.payload = payload;
        base.quality = quality;
        base.addresses = addresses;
        delete base.errors;
        send(base);
        return;
      }
      const row = table.rowValues(values);
      const rows = mode === 'changes' ? changes.changedRows(table, row) : undefined;
      const n = rows ? rows.length : row.length;
      if (n === 0) return;
      // The messages of one read share one id, as the messages of one send([msgs]) call do.
      const id = base ? undefined : RED.util.generateId();
      for (let k = 0; k < n; k++) {
        const i = rows ? rows[k] : k;
        send(rowMessage(i, row[i], base && k < n - 1 ? RED.util.cloneMessage(base) : base, id));
      }
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
      serial(readTable)
        .then(
          (read) => {
            if (closing) return;
            const send = (m) => node.send(m);
            if (read.values) {
              showQuality(0);
              emitGood(send, read.values, undefined, output);
              reported.clear();
              return;
            }
            const { list } = read;
            showQuality(list.filter((o) => !o.ok).length);
            emit(send, list, undefined, output);
            const bad = list.filter((o) => !o.ok && !reported.has(o.name));
            for (const o of list) if (o.ok) reported.delete(o.name);
            if (bad.length > 0) {
              bad.forEach((o) => reported.add(o.name));
              node.error(tagFailure('read', bad), { topic, payload: Object.fromEntries(bad.map((o) => [o.name, o.error])) });
            }
          },
          (err) => {
            // A lost link shows on the status and reaches Catch through the connection; anything else is reported here.
            if (!closing && !isLinkError(err)) {
              node.error(err, { topic, payload: {} });
            }
          },
        )
        .finally(() => {
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
      serial(() => (asked ? readList(asked) : readTable())).then(
        (read) => {
          if (read.values) {
            showQuality(0);
            emitGood(send, read.values, msg, output);
            done();
            return;
          }
          const results = read.list;
          // On-demand addresses have no history to compare with: 'changes' sends them one per tag.
          const mode = asked && output === 'changes' ? 'per-tag' : output;
          if (!asked) showQuality(results.filter((o) => !o.ok).length);
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
