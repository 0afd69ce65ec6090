'use strict';
// bench-count: counts the messages it receives in a process-wide counter that
// bench/nodered-worker.js reads (and, while `track` is on, which topics came).
module.exports = function (RED) {
  const counter = (global.__plcwireBenchCount ??= { messages: 0, track: false, topics: new Set() });
  function BenchCount(config) {
    RED.nodes.createNode(this, config);
    this.on('input', (msg) => {
      counter.messages++;
      if (counter.track) counter.topics.add(msg.topic);
    });
  }
  RED.nodes.registerType('bench-count', BenchCount);
};
