'use strict';
const { SparkplugEdgeHub } = require('..');

/**
 * plcwire-sparkplug-edge (config node): one Sparkplug B edge node (brokers,
 * group, node id, primary host, state directory, store-and-forward bound
 * and the directory it keeps its values in).
 * The plcwire-sparkplug-device nodes add their PLCs to it; the edge node
 * starts once the flows have started and sends NDEATH when they stop.
 * The logic is lib/flows/sparkplug-edge.ts.
 */
module.exports = function (RED) {
  function PlcwireSparkplugEdge(config) {
    RED.nodes.createNode(this, config);
    const node = this;
    const creds = node.credentials || {};
    // The CA, client certificate and key of Node-RED's tls-config node, for mqtts:// and wss:// brokers.
    const tlsNode = config.tls ? RED.nodes.getNode(config.tls) : null;
    const tls = {};
    if (tlsNode) tlsNode.addTLSOptions(tls);
    try {
      node.hub = new SparkplugEdgeHub({
        brokers: config.brokers,
        group: config.group,
        node: config.nodeId,
        primaryHost: config.primaryHost,
        stateDir: config.stateDir,
        buffer: config.buffer,
        bufferDir: config.bufferDir,
        interval: config.interval,
        username: creds.username,
        password: creds.password,
        ...(tlsNode ? { tls } : {}),
      });
    } catch (err) {
      node.problem = err;
      node.error(err);
      return;
    }
    // Errors and status reach the device nodes (a config node has no tab, so no Catch hears it).
    node.hub.on('error', () => undefined);
    const start = () => node.hub.start();
    RED.events.once('flows:started', start);
    node.on('close', (done) => {
      RED.events.removeListener('flows:started', start);
      node.hub.close().then(
        () => done(),
        () => done(),
      );
    });
  }
  RED.nodes.registerType('plcwire-sparkplug-edge', PlcwireSparkplugEdge, {
    credentials: { username: { type: 'text' }, password: { type: 'password' } },
  });
};
