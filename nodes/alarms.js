'use strict';
const { attach, settleWithin } = require('./shared/user');
const plc = require('..');
const { alarmCountsStatus, alarmsFailedStatus } = require('./shared/status');
const { driverOf, schemesOffering } = require('../dist/lib/drivers');
const { AlarmFeed, requestOf } = require('../dist/lib/flows/alarms');
const { eventTopic, plainAlarm, plainEvent } = require('../dist/lib/alarms/show');

/**
 * plcwire-alarms: what the PLC reports of its alarms (S7-300/400 over
 * s7://, S7-1200/1500 over s7plus://), one message per event as the PLC
 * sent it (msg.payload the event, msg.topic `alarm/<id>/<change>`); an
 * input `msg.ack = <id>` acknowledges that alarm (an operator's write: the
 * connection's readOnly and allow-list refuse it), `msg.topic = "list"`
 * sends the active alarms. The status shows the active and unacknowledged
 * counts; errors go to Catch, once per outage. The logic is
 * lib/flows/alarms.ts.
 */
module.exports = function (RED) {
  function PlcwireAlarms(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const options = {
      mode: config.mode === true || config.mode === 'true',
      diagnostics: config.diagnostics === true || config.diagnostics === 'true',
    };
    let feed;
    let lastCounts;
    let closing = false;

    const showCounts = () => {
      if (lastCounts && feed && feed.subscribed) node.status(alarmCountsStatus(RED._, lastCounts));
    };
    // Connected: the counts say more than "connected" once the subscription is up.
    const connection = attach(RED, node, config.connection, (status) => {
      if (status.state === 'connected' && feed && feed.subscribed && lastCounts) {
        showCounts();
        return false;
      }
      return true;
    });

    /** The feed of the connection's client, made when the client exists and its driver serves alarms; else the reason. */
    function feedOf() {
      if (feed) return feed;
      if (!connection) throw withCode(new Error(RED._('plcwire.errors.noConnection')), 'NOT_CONNECTED');
      if (connection.problem) throw connection.problem;
      const client = connection.client;
      if (!client) throw withCode(new Error(RED._('plcwire.errors.noConnection')), 'NOT_CONNECTED');
      const port = driverOf(client.endpoint).alarms;
      if (!port) {
        throw new plc.PlcError(
          'NOT_SUPPORTED',
          RED._('plcwire-alarms.errors.noAlarms', { protocol: client.endpoint.protocol, schemes: schemesOffering('alarms') || '-' }),
        );
      }
      feed = new AlarmFeed(client, port, options, {
        event(e) {
          if (closing) return;
          node.send({ topic: eventTopic(e), payload: plainEvent(e) });
        },
        counts(c) {
          lastCounts = c;
          if (!closing) showCounts();
        },
        error(err, first) {
          if (closing) return;
          node.status(alarmsFailedStatus(RED._));
          if (first) node.error(err, { topic: 'alarms', payload: { code: err.code, message: err.message } });
        },
      });
      return feed;
    }

    // Subscribe as soon as the flows run (errors of a node being created would reach no Catch node).
    const start = () => {
      try {
        feedOf();
      } catch (err) {
        if (!closing && connection && !connection.problem) {
          node.status(alarmsFailedStatus(RED._));
          node.error(err, { topic: 'alarms', payload: { code: err.code, message: err.message } });
        }
      }
    };
    RED.events.once('flows:started', start);

    node.on('input', function (msg, send, done) {
      let request;
      let f;
      try {
        request = requestOf(msg);
        f = feedOf();
      } catch (err) {
        done(err);
        return;
      }
      const work = 'ack' in request ? f.acknowledge(request.ack, request.signal8).then(() => undefined) : f.list();
      work
        .then((list) => {
          if (closing) return done();
          if (list) {
            msg.topic = 'list';
            msg.payload = list.map(plainAlarm);
            send(msg);
          }
          done();
        })
        .catch((err) => (closing ? done() : done(err)));
    });

    node.on('close', function (removed, done) {
      closing = true;
      RED.events.removeListener('flows:started', start);
      settleWithin(Promise.all([feed ? feed.close() : undefined, connection ? connection.detach() : undefined])).then(() => done());
    });
  }

  function withCode(err, code) {
    err.code = code;
    return err;
  }

  RED.nodes.registerType('plcwire-alarms', PlcwireAlarms);
};
