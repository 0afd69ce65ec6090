'use strict';
const { attach, settleWithin, liveClient, warnDuplicateNames } = require('./shared/user');
const { tagTable, tagsOfMessage, outcomes, tagFailure, ChangeFilter, PolledTable, PlcError, isLinkError, realsForPeople } = require('..');
const { ReadQueue } = require('../dist/lib/flows/read-queue');
const { ReadMessages, readOutput } = require('../dist/lib/flows/read-messages');
const { ReadPush, canPush, refusedForGood } = require('../dist/lib/flows/read-push');
const { tagErrorsStatus } = require('./shared/status');

/** Each address once, in table order (a table may name one address twice). */
function uniqueAddresses(list) {
  return [...new Set(list.map((t) => t.address))];
}

/**
 * plcwire-read: polls `tags` every `interval` ms (0 = only on input) and
 * reads on every input message (`msg.tags` reads other addresses on demand).
 * Reads run one at a time (ReadQueue): a poll never overlaps the previous
 * one. A read of the configured table in which every tag succeeded (the
 * common case) is sent from the client's values by address, any other from
 * per-tag outcomes; ReadMessages builds the messages of both.
 *
 * Mode "push" (s7plus://, and s7:// on S7-300/400: cyclic data): no polling; the PLC reports changes of the
 * table (ReadPush, a subscription on the client), sent as the polled mode's
 * change messages; input messages still read at once.
 */
module.exports = function (RED) {
  function PlcwireRead(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const tags = tagTable(config.tags);
    warnDuplicateNames(RED, node, tags);
    const pushed = config.mode === 'push';
    const interval = pushed ? 0 : Math.max(0, Number(config.interval) || 0);
    const output = pushed ? 'changes' : readOutput(config.output);
    const changes = new ChangeFilter(config.deadband);
    const topic = node.name || 'plcwire';
    let timer;
    let closing = false;
    const queue = new ReadQueue();
    let failing = false;
    /** What the node's status shows: 'link' (the connection's state) or 'tags' (how many failed). */
    let shown;
    /** Names of tags whose failure was already reported to Catch (reported again only after they recover). */
    const reported = new Set();

    const connection = attach(RED, node, config.connection, (status) => {
      const show = status.state !== 'connected' || !failing;
      if (status.state === 'connected' && interval > 0) schedule(0);
      // After attach() has returned: it calls this at once with the current state.
      if (status.state === 'connected' && pushed) process.nextTick(subscribe);
      if (show) shown = 'link';
      return show;
    });

    // The configured table, made ready once: the client recognises the address
    // array it has seen (its parsed tags, plan and request frames are kept for
    // it), so every read of the table passes the same array.
    const table = new PolledTable(tags);
    const messages = new ReadMessages(table, output, topic, changes, {
      clone: (msg) => RED.util.cloneMessage(msg),
      newId: () => RED.util.generateId(),
    });

    /**
     * Reads the table: { values } by address when every tag succeeded,
     * else { list } of per-tag outcomes. A failure of the whole read rejects.
     */
    async function readTable() {
      const client = liveClient(RED, connection);
      try {
        return { values: realsShown(client, await client.read(table.addresses)) };
      } catch (err) {
        if (err && err.code === 'TAG_ERRORS' && err.results) return { list: outcomesShown(client, outcomes(tags, err.results)) };
        throw err;
      }
    }

    async function readList(list) {
      const client = liveClient(RED, connection);
      const results = await client.readDetailed(uniqueAddresses(list));
      return { list: outcomesShown(client, outcomes(list, results)) };
    }

    // REAL values in messages with the digits TIA shows (40.4, not 40.400001525878906): how to show each
    // address is found once per client (a new connection config makes a new one) and address.
    const shows = new WeakMap();
    function showOf(client, address) {
      let byAddress = shows.get(client);
      if (!byAddress) shows.set(client, (byAddress = new Map()));
      if (!byAddress.has(address)) {
        let convert;
        try {
          convert = realsForPeople(client, connection ? connection.symbols : undefined, address);
        } catch {
          convert = undefined; // an address the client refuses: its read failed already
        }
        byAddress.set(address, convert);
      }
      return byAddress.get(address);
    }
    /** Per client: the table's addresses that hold a REAL, each with its conversion (a poll converts those only). */
    const realPlans = new WeakMap();
    function realsShown(client, values) {
      let plan = realPlans.get(client);
      if (plan === undefined) {
        plan = [];
        for (const address of table.addresses) {
          const convert = showOf(client, address);
          if (convert) plan.push(address, convert);
        }
        realPlans.set(client, plan);
      }
      for (let i = 0; i < plan.length; i += 2) values[plan[i]] = plan[i + 1](values[plan[i]]);
      return values;
    }
    function outcomesShown(client, list) {
      for (const o of list) {
        const convert = o.ok ? showOf(client, o.address) : undefined;
        if (convert) o.value = convert(o.value);
      }
      return list;
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

    /** Outcomes of a poll or a notification: the status, the messages, each newly failed tag to Catch once. */
    function deliver(list, send = (m) => node.send(m)) {
      showQuality(list.filter((o) => !o.ok).length);
      messages.sendOutcomes(send, list);
      const bad = list.filter((o) => !o.ok && !reported.has(o.name));
      for (const o of list) if (o.ok) reported.delete(o.name);
      if (bad.length > 0) {
        bad.forEach((o) => reported.add(o.name));
        node.error(tagFailure('read', bad), { topic, payload: Object.fromEntries(bad.map((o) => [o.name, o.error])) });
      }
    }

    // Push mode: the table subscribed when the link is up; the client subscribes again after a reconnect.
    const push = pushed
      ? new ReadPush(tags, Math.max(10, Number(config.cycle) || 100), {
          outcomes: (list) => {
            if (closing) return;
            try {
              deliver(outcomesShown(liveClient(RED, connection), list));
            } catch (err) {
              node.error(err, { topic, payload: {} });
            }
          },
          active: () => {
            if (!failing && connection) connection.showLink();
          },
          failed: (err) => {
            if (closing) return;
            // A lost link with the connection's own link down is the connection's to report (Status and Catch), as when polling.
            if (isLinkError(err) && node.linkState !== 'connected') return;
            const refused = refusedForGood(err);
            node.status(
              refused
                ? { fill: 'red', shape: 'ring', text: RED._('plcwire-read.status.noPush') }
                : { fill: 'yellow', shape: 'ring', text: RED._('plcwire-read.status.resubscribing') },
            );
            node.error(err, { topic, payload: {} });
          },
        })
      : undefined;
    let pushRefused = false;
    function subscribe() {
      if (closing || !push) return;
      let client;
      try {
        client = liveClient(RED, connection);
      } catch {
        return; // the connection reports why
      }
      if (canPush(client)) return push.linkUp(client);
      if (pushRefused) return;
      pushRefused = true;
      node.status({ fill: 'red', shape: 'ring', text: RED._('plcwire-read.status.noPush') });
      node.error(new PlcError('NOT_SUPPORTED', RED._('plcwire-read.errors.pushProtocol', { protocol: client.protocol })), {
        topic,
        payload: {},
      });
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
      queue
        .run(readTable)
        .then(
          (read) => {
            if (closing) return;
            const send = (m) => node.send(m);
            if (read.values) {
              showQuality(0);
              messages.sendGood(send, read.values);
              reported.clear();
              return;
            }
            deliver(read.list);
          },
          (err) => {
            // A lost link shows on the status and reaches Catch through the connection; anything else is reported
            // here, unless it took the link down with it (a timeout that ends the connection): the connection reports that.
            if (!closing && !isLinkError(err) && node.linkState === 'connected') {
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
      queue
        .run(() => (asked ? readList(asked) : readTable()))
        .then(
          (read) => {
            if (read.values) {
              showQuality(0);
              messages.sendGood(send, read.values, msg);
              done();
              return;
            }
            const results = read.list;
            if (!asked) showQuality(results.filter((o) => !o.ok).length);
            messages.sendOutcomes(send, results, msg, !!asked);
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
      settleWithin(Promise.all([push ? push.close() : undefined, connection ? connection.detach() : undefined])).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-read', PlcwireRead);
};
