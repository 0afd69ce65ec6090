'use strict';
const { attach, settleWithin, liveClient } = require('./shared/user');
const { LifeSignWatch, nextLifeSign, isLinkError } = require('..');
const { linkStatus, sentStatus, aliveStatus, lostStatus, waitingStatus } = require('./shared/status');

/**
 * plcwire-heartbeat: every `interval` ms writes the PC's life sign
 * (`writeAddress`, counter or toggle) and reads the PLC's (`watchAddress`),
 * which must change within `timeout` ms. Sends `alive`, `lost`, `restored`.
 */
module.exports = function (RED) {
  function PlcwireHeartbeat(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const writeAddress = String(config.writeAddress || '').trim();
    const watchAddress = String(config.watchAddress || '').trim();
    const writeMode = config.writeMode === 'toggle' ? 'toggle' : 'counter';
    const interval = Math.max(100, Number(config.interval) || 1000);
    const timeout = Math.max(interval, Number(config.timeout) || 3 * interval);
    const watch = watchAddress ? new LifeSignWatch({ timeout }) : undefined;
    const watchList = [watchAddress]; // one array for every beat: the client keeps its plan for it
    let lifeSign = writeMode === 'toggle' ? false : 0;
    let written = 0;
    let timer;
    let closing = false;
    let lastProblem = '';

    // Connected, or lost whatever the link does: the life sign is what this node's status shows.
    const connection = attach(RED, node, config.connection, (status) => {
      if (status.state !== 'connected' && !(watch && watch.state === 'lost')) return true;
      showState();
      return false;
    });

    function showState() {
      if (!watch) {
        if (node.linkState === 'connected') node.status(sentStatus(RED._, written));
        else node.status(linkStatus(RED._, { state: node.linkState }));
        return;
      }
      if (watch.state === 'lost') {
        node.status(lostStatus(RED._, watch.age));
      } else if (watch.state === 'alive' && node.linkState === 'connected') {
        node.status(aliveStatus(RED._, watch.changes));
      } else if (node.linkState === 'connected') {
        node.status(waitingStatus(RED._));
      }
    }

    function problem(err) {
      const text = err.message;
      if (text === lastProblem) return;
      lastProblem = text;
      node.error(err, { topic: node.name || 'heartbeat', payload: { address: err.tag } });
    }

    async function exchange(client) {
      if (writeAddress) {
        let type = 'INT';
        try {
          type = client.tag(writeAddress).type;
        } catch {
          // the write below reports the bad address
        }
        const next = nextLifeSign(writeMode, lifeSign, type);
        const results = await client.writeDetailed({ [writeAddress]: next });
        const r = results[writeAddress];
        if (r && r.ok) {
          lifeSign = next;
          written++;
        } else if (r) throw Object.assign(r.error, { tag: writeAddress });
      }
      if (watch) {
        const r = (await client.readDetailed(watchList))[watchAddress];
        if (!r || !r.ok) throw Object.assign(r ? r.error : new Error('no result'), { tag: watchAddress });
        const event = watch.observe(r.value);
        if (event) node.send({ topic: node.name || 'heartbeat', payload: watch.report(event) });
      }
      lastProblem = '';
    }

    function tick() {
      timer = undefined;
      const started = Date.now();
      // While the link is up: the client by the check every node uses (liveClient); what it throws goes where exchange's errors go.
      let work = Promise.resolve();
      if (node.linkState === 'connected') {
        try {
          work = exchange(liveClient(RED, connection));
        } catch (err) {
          work = Promise.reject(err);
        }
      }
      work
        .catch((err) => {
          if (!closing && !isLinkError(err)) problem(err);
        })
        .then(() => {
          if (closing) return;
          const event = watch && watch.check();
          if (event) node.send({ topic: node.name || 'heartbeat', payload: watch.report(event) });
          showState();
          timer = setTimeout(tick, Math.max(0, interval - (Date.now() - started)));
        });
    }

    if (connection) timer = setTimeout(tick, 0);

    node.on('close', function (removed, done) {
      closing = true;
      clearTimeout(timer);
      timer = undefined;
      settleWithin(connection ? connection.detach() : undefined).then(() => done());
    });
  }

  RED.nodes.registerType('plcwire-heartbeat', PlcwireHeartbeat);
};
