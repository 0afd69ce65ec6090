'use strict';
const { attach, settleWithin } = require('./shared/user');

/**
 * plcwire-sparkplug-device: a PLC (a plcwire-connection and a table of its
 * tags) as a Sparkplug B device of a plcwire-sparkplug-edge node. Its status
 * is the edge node's session; a DCMD write that reached the PLC is sent on
 * as a message, one that was refused is an error a Catch node hears. With
 * "publish the PLC's alarms" the device also carries the PLC's alarms as its
 * `Alarms/…` metrics, and hosts may acknowledge them when that box is set.
 */
module.exports = function (RED) {
  const STATES = {
    online: { fill: 'green', shape: 'dot' },
    'waiting-for-host': { fill: 'yellow', shape: 'ring' },
    connecting: { fill: 'yellow', shape: 'ring' },
    stopped: { fill: 'grey', shape: 'ring' },
  };

  function PlcwireSparkplugDevice(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const deviceName = String(config.device || '').trim();
    const edge = config.edge ? RED.nodes.getNode(config.edge) : null;
    let published = 0;
    let linkDown = false;
    /** The edge node refused this device (its settings): the status says so until the next deploy. */
    let refused = false;

    const showStatus = (s) => {
      if (linkDown || refused) return;
      const look = STATES[s.state] || STATES.stopped;
      const key = s.state === 'online' && published > 0 ? 'onlineCount' : STATES[s.state] ? s.state : 'stopped';
      node.status({ ...look, text: RED._(`plcwire-sparkplug-device.status.${key}`, { n: published }) });
    };

    // The link's status: the PLC lost is the device's death (DDEATH); back, the edge node's state again.
    const connection = attach(RED, node, config.connection, (status) => {
      linkDown = status.state !== 'connected';
      if (!linkDown && edge && edge.hub) showStatus(edge.hub.status);
      return linkDown;
    });
    if (!edge || !edge.hub) {
      node.status({ fill: 'red', shape: 'ring', text: RED._('plcwire-sparkplug-device.status.noEdge') });
      if (edge && edge.problem) node.error(edge.problem);
      return;
    }
    if (!connection || !connection.client) return;
    const hub = edge.hub;
    let reportRefusal;
    const onStatus = (s) => showStatus(s);
    const onPublish = (m) => {
      if (m.device !== deviceName || m.type !== 'DDATA') return;
      published++;
      showStatus(hub.status);
    };
    const onCommand = (done) => {
      if (done.device !== deviceName) return;
      node.send({ topic: `${deviceName}/${done.metric}`, payload: { device: done.device, metric: done.metric, value: done.value } });
    };
    const onError = (err, device) => {
      // Another device's error is that node's; the edge node's own (no device) go to every device node.
      if (device !== undefined && device !== deviceName) return;
      node.error(err, { topic: deviceName, payload: { code: err.code, tag: err.tag } });
    };
    hub.on('status', onStatus);
    hub.on('publish', onPublish);
    hub.on('command', onCommand);
    hub.on('error', onError);
    try {
      hub.add({
        name: deviceName,
        client: connection.client,
        tags: config.tags,
        writable: config.writable,
        symbols: connection.symbols,
        deadband: Number(config.deadband) || 0,
        alarms: config.alarms === true,
        acknowledge: config.alarms === true && config.acknowledge === true,
      });
      showStatus(hub.status);
    } catch (err) {
      refused = true;
      node.status({ fill: 'red', shape: 'ring', text: RED._('plcwire-sparkplug-device.status.badConfig') });
      // Raised once the flows have started, so a Catch node created after this one hears it too.
      reportRefusal = () => node.error(err, { topic: deviceName, payload: { code: err.code, tag: err.tag } });
      RED.events.once('flows:started', reportRefusal);
    }
    node.on('close', (done) => {
      if (reportRefusal) RED.events.removeListener('flows:started', reportRefusal);
      hub.removeListener('status', onStatus);
      hub.removeListener('publish', onPublish);
      hub.removeListener('command', onCommand);
      hub.removeListener('error', onError);
      hub.remove(deviceName);
      connection.detach();
      settleWithin(Promise.resolve()).then(() => done());
    });
  }
  RED.nodes.registerType('plcwire-sparkplug-device', PlcwireSparkplugDevice);
};
