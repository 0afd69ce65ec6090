'use strict';
// Flows for bench/nodered.js: one connection and one read node per PLC, all
// wired to one bench-count node, for our nodes and for node-red-contrib-s7.
const { plcTable } = require('./fleet');

const at = { x: 200, y: 100 };

/** Tag names as a flow has them (tag001, …), the same for both packages. */
function tagName(k) {
  return `tag${String(k + 1).padStart(3, '0')}`;
}

/**
 * Our nodes: per PLC a plcwire-connection and a plcwire-read named plc<i>
 * polling every `intervalMs` in `output` mode ('object' | 'per-tag' | 'changes').
 */
function oursFlow({ ports, tags, intervalMs, output }) {
  const nodes = [
    { id: 'tab', type: 'tab', label: 'bench' },
    { id: 'count', type: 'bench-count', z: 'tab', ...at },
  ];
  ports.forEach((port, i) => {
    nodes.push({ id: `conn${i}`, type: 'plcwire-connection', name: `plc${i}`, url: `s7://127.0.0.1:${port}?rack=0&slot=1&pdu=960` });
    nodes.push({
      id: `read${i}`,
      type: 'plcwire-read',
      z: 'tab',
      name: `plc${i}`,
      connection: `conn${i}`,
      interval: intervalMs,
      output,
      deadband: 0,
      tags: plcTable(tags, i).map((t, k) => ({ name: tagName(k), address: t.address })),
      wires: [['count']],
      ...at,
    });
  });
  return nodes;
}

/**
 * node-red-contrib-s7: per PLC an `s7 endpoint` polling every `intervalMs`
 * (the cycle time is the endpoint's) and an `s7 in` node in `mode`
 * ('all' = one object, 'all-split' = one message per tag), `diff` = only changes.
 */
function contribFlow({ ports, tags, intervalMs, mode, diff }) {
  const nodes = [
    { id: 'tab', type: 'tab', label: 'bench' },
    { id: 'count', type: 'bench-count', z: 'tab', ...at },
  ];
  ports.forEach((port, i) => {
    nodes.push({
      id: `ep${i}`,
      type: 's7 endpoint',
      transport: 'iso-on-tcp',
      address: '127.0.0.1',
      port: String(port),
      rack: '0',
      slot: '1',
      localtsaphi: '01',
      localtsaplo: '00',
      remotetsaphi: '01',
      remotetsaplo: '01',
      connmode: 'rack-slot',
      adapter: '',
      busaddr: '2',
      cycletime: String(intervalMs),
      timeout: '2000',
      name: `plc${i}`,
      vartable: plcTable(tags, i).map((t, k) => ({ addr: t.address, name: tagName(k) })),
    });
    nodes.push({
      id: `in${i}`,
      type: 's7 in',
      z: 'tab',
      endpoint: `ep${i}`,
      mode,
      variable: '',
      diff: !!diff,
      name: `plc${i}`,
      wires: [['count']],
      ...at,
    });
  });
  return nodes;
}

module.exports = { oursFlow, contribFlow, tagName };
