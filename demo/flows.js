'use strict';
/**
 * The demo flow deployed by `npm start`: for each protocol a connection, a
 * poll feeding a Dashboard 2.0 page, and for S7 a switch that writes back and
 * a heartbeat. Generated here (not a JSON blob) so the URLs follow the ports.
 */

/** @param {{ s7: string, fetchwrite: string, freeport: string }} urls */
function demoFlow(urls) {
  const tab = 'demo.tab';
  const nodes = [];
  let y = 60;
  const at = (x) => ({ x, y, z: tab });
  const row = () => (y += 70);

  nodes.push({ id: tab, type: 'tab', label: 'plcwire demo', info: 'Simulated PLCs started by `npm start`.' });
  nodes.push({
    id: 'demo.comment',
    type: 'comment',
    name: 'Simulators: started by npm start (S7 10102, FETCH/WRITE 12000/12001, freeport tcp 14001)',
    info: 'Run `npx plcwire demo` to start the same simulated plant without Node-RED.',
    ...at(330),
  });
  nodes.push({
    id: 'demo.comment.dashboard',
    type: 'comment',
    name: 'Needs @flowfuse/node-red-dashboard (Dashboard 2.0); page at /dashboard/plant',
    info: 'Install Dashboard 2.0 from the palette manager: @flowfuse/node-red-dashboard.',
    ...at(330),
    y: 100,
  });

  // Dashboard 2.0 skeleton.
  nodes.push({ id: 'ui.base', type: 'ui-base', name: 'plcwire', path: '/dashboard', includeClientData: true, acceptsClientConfig: ['ui-notification', 'ui-control'], showPathInSidebar: false, navigationStyle: 'default', titleBarStyle: 'default' });
  nodes.push({ id: 'ui.theme', type: 'ui-theme', name: 'plcwire', colors: { surface: '#1f3a5f', primary: '#0d74ce', bgPage: '#f9f9fb', groupBg: '#ffffff', groupOutline: '#d9d9e0' }, sizes: { density: 'default', pagePadding: '12px', groupGap: '12px', groupBorderRadius: '4px', widgetGap: '12px' } });
  nodes.push({ id: 'ui.page', type: 'ui-page', name: 'Plant', ui: 'ui.base', path: '/plant', icon: 'factory', layout: 'grid', theme: 'ui.theme', order: 1, visible: 'true', disabled: 'false', breakpoints: [{ name: 'Default', px: 0, cols: 3 }, { name: 'Tablet', px: 576, cols: 6 }, { name: 'Small Desktop', px: 768, cols: 9 }, { name: 'Desktop', px: 1024, cols: 12 }] });
  const group = (id, name, order) => nodes.push({ id, type: 'ui-group', name, page: 'ui.page', width: 6, height: 1, order, showTitle: true, visible: 'true', disabled: 'false', groupType: 'default' });
  group('ui.g.s7', 'S7-1200 (S7comm)', 1);
  group('ui.g.other', 'CP (FETCH/WRITE) and S7-200 (freeport)', 2);
  const text = (id, g, label, order, wires = []) =>
    nodes.push({ id, type: 'ui-text', group: g, order, width: 0, height: 0, name: label, label, format: '{{msg.payload}}', layout: 'row-spread', style: false, value: 'payload', valueType: 'msg', className: `plcwire-${id.replace(/\W/g, '-')}`, ...at(1050), wires });

  // Connections: one per PLC, shared by every node below.
  nodes.push({ id: 'conn.s7', type: 'plcwire-connection', name: 'S7-1200 sim', url: urls.s7 });
  nodes.push({ id: 'conn.fw', type: 'plcwire-connection', name: 'CP fetch/write sim', url: urls.fetchwrite });
  nodes.push({ id: 'conn.fp', type: 'plcwire-connection', name: 'S7-200 freeport sim', url: urls.freeport });

  // S7: poll the process, one message per tag, routed by topic.
  row();
  nodes.push({
    id: 's7.read', type: 'plcwire-read', name: 'poll S7', connection: 'conn.s7', interval: 500, output: 'per-tag', deadband: 0,
    tags: [
      { name: 'level', address: 'DB1.DBD0:REAL' },
      { name: 'running', address: 'DB1.DBX4.1' },
      { name: 'speed', address: 'DB1.DBW6:INT' },
      { name: 'parts', address: 'DB1.DBD8:DINT' },
      { name: 'temperature', address: 'DB1.DBD16:REAL' },
    ],
    ...at(160), wires: [['s7.route']],
  });
  nodes.push({
    id: 's7.route', type: 'switch', name: 'by tag', property: 'topic', propertyType: 'msg', checkall: 'false', outputs: 5,
    rules: ['level', 'running', 'speed', 'parts', 'temperature'].map((v) => ({ t: 'eq', v, vt: 'str' })),
    ...at(360), wires: [['s7.round.level'], ['ui.running'], ['ui.speed'], ['ui.parts'], ['s7.round']],
  });
  nodes.push({ id: 's7.round.level', type: 'change', name: 'one decimal', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: '$round(payload, 1)', tot: 'jsonata' }], ...at(560), y: y - 40, wires: [['ui.level', 'ui.chart']] });
  nodes.push({ id: 's7.round', type: 'change', name: 'one decimal', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: '$round(payload, 1)', tot: 'jsonata' }], ...at(560), wires: [['ui.temp', 'ui.chart']] });
  nodes.push({ id: 'ui.level', type: 'ui-gauge', name: 'Tank level', group: 'ui.g.s7', order: 1, width: 3, height: 3, gtype: 'gauge-half', gstyle: 'needle', title: 'Tank level', units: '%', min: 0, max: 100, segments: [{ from: 0, color: '#5cd65c' }, { from: 80, color: '#ffc800' }, { from: 90, color: '#ea5353' }], sizeThickness: 16, sizeGap: 4, sizeKeyThickness: 8, styleRounded: true, styleGlow: false, className: 'plcwire-level', ...at(800), wires: [] });
  nodes.push({ id: 'ui.chart', type: 'ui-chart', name: 'Level and temperature', group: 'ui.g.s7', order: 2, width: 6, height: 6, label: 'Level % and temperature °C', chartType: 'line', category: 'topic', categoryType: 'msg', xAxisType: 'time', xAxisPropertyType: 'timestamp', yAxisProperty: 'payload', yAxisPropertyType: 'msg', action: 'append', removeOlder: 2, removeOlderUnit: '60', removeOlderPoints: '', showLegend: true, pointShape: 'circle', pointRadius: 2, interpolation: 'linear', colors: ['#0095FF', '#FF7F0E'], className: 'plcwire-chart', ...at(820), wires: [] });
  text('ui.running', 'ui.g.s7', 'Motor running', 4);
  text('ui.speed', 'ui.g.s7', 'Speed (rpm)', 5);
  text('ui.parts', 'ui.g.s7', 'Parts', 6);
  text('ui.temp', 'ui.g.s7', 'Temperature (°C)', 7);

  // S7: the operator's switch writes the motor command back to the PLC.
  row();
  nodes.push({ id: 'ui.motor', type: 'ui-switch', name: 'Motor', label: 'Motor run', group: 'ui.g.s7', order: 3, width: 0, height: 0, passthru: false, decouple: false, topic: 'DB1.DBX4.0', topicType: 'str', onvalue: true, onvalueType: 'bool', offvalue: false, offvalueType: 'bool', layout: 'row-spread', clickableArea: 'switch', className: 'plcwire-motor', ...at(160), wires: [['s7.write']] });
  nodes.push({ id: 's7.write', type: 'plcwire-write', name: 'write motor', connection: 'conn.s7', tags: [], ...at(360), wires: [[]] });

  // S7: heartbeat — our counter to DB1.DBW14, the PLC's counter in DB1.DBW12 must keep changing.
  row();
  nodes.push({ id: 's7.heartbeat', type: 'plcwire-heartbeat', name: 'S7 life sign', connection: 'conn.s7', writeAddress: 'DB1.DBW14:INT', writeMode: 'counter', interval: 1000, watchAddress: 'DB1.DBW12:INT', timeout: 3000, ...at(160), wires: [['s7.hbtext']] });
  nodes.push({ id: 's7.hbtext', type: 'change', name: 'event name', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: 'payload.event', tot: 'msg' }], ...at(360), wires: [['ui.heartbeat']] });
  text('ui.heartbeat', 'ui.g.s7', 'PLC heartbeat', 8);

  // Link states of the three connections, from the read nodes' status.
  row();
  nodes.push({ id: 'st.s7', type: 'status', name: 'S7 link', scope: ['s7.read'], ...at(160), wires: [['st.text.s7']] });
  nodes.push({ id: 'st.text.s7', type: 'change', name: 'status text', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: "$replace(status.text, 'plcwire.status.', '')", tot: 'jsonata' }], ...at(360), wires: [['ui.link.s7']] });
  text('ui.link.s7', 'ui.g.s7', 'S7 link', 9);

  // FETCH/WRITE: the same DB1 through the CP.
  row();
  nodes.push({
    id: 'fw.read', type: 'plcwire-read', name: 'poll CP', connection: 'conn.fw', interval: 1000, output: 'per-tag', deadband: 0,
    tags: [
      { name: 'level', address: 'DB1,REAL0' },
      { name: 'parts', address: 'DB1,DINT8' },
    ],
    ...at(160), wires: [['fw.route']],
  });
  nodes.push({ id: 'fw.route', type: 'switch', name: 'by tag', property: 'topic', propertyType: 'msg', checkall: 'false', outputs: 2, rules: [{ t: 'eq', v: 'level', vt: 'str' }, { t: 'eq', v: 'parts', vt: 'str' }], ...at(360), wires: [['fw.round'], ['ui.fw.parts']] });
  nodes.push({ id: 'fw.round', type: 'change', name: 'one decimal', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: '$round(payload, 1)', tot: 'jsonata' }], ...at(560), wires: [['ui.fw.level']] });
  text('ui.fw.level', 'ui.g.other', 'CP: tank level (%)', 1);
  text('ui.fw.parts', 'ui.g.other', 'CP: parts', 2);
  nodes.push({ id: 'st.fw', type: 'status', name: 'CP link', scope: ['fw.read'], ...at(160), wires: [['st.text.fw']] });
  nodes.push({ id: 'st.text.fw', type: 'change', name: 'status text', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: "$replace(status.text, 'plcwire.status.', '')", tot: 'jsonata' }], ...at(360), wires: [['ui.link.fw']] });
  text('ui.link.fw', 'ui.g.other', 'CP link', 3);

  // Freeport: stations 5 (level, REAL) and 6 (parts, DINT) on the RS-485 bus, through a serial device server.
  row();
  nodes.push({
    id: 'fp.read', type: 'plcwire-read', name: 'poll S7-200', connection: 'conn.fp', interval: 1000, output: 'per-tag', deadband: 0,
    tags: [
      { name: 'level', address: 'ST5,REAL0' },
      { name: 'parts', address: 'ST6,DINT0' },
    ],
    ...at(160), wires: [['fp.route']],
  });
  nodes.push({ id: 'fp.route', type: 'switch', name: 'by tag', property: 'topic', propertyType: 'msg', checkall: 'false', outputs: 2, rules: [{ t: 'eq', v: 'level', vt: 'str' }, { t: 'eq', v: 'parts', vt: 'str' }], ...at(360), wires: [['fp.round'], ['ui.fp.parts']] });
  nodes.push({ id: 'fp.round', type: 'change', name: 'one decimal', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: '$round(payload, 1)', tot: 'jsonata' }], ...at(560), wires: [['ui.fp.level']] });
  text('ui.fp.level', 'ui.g.other', 'S7-200: tank level (%)', 4);
  text('ui.fp.parts', 'ui.g.other', 'S7-200: parts', 5);
  nodes.push({ id: 'st.fp', type: 'status', name: 'S7-200 link', scope: ['fp.read'], ...at(160), wires: [['st.text.fp']] });
  nodes.push({ id: 'st.text.fp', type: 'change', name: 'status text', rules: [{ t: 'set', p: 'payload', pt: 'msg', to: "$replace(status.text, 'plcwire.status.', '')", tot: 'jsonata' }], ...at(360), wires: [['ui.link.fp']] });
  text('ui.link.fp', 'ui.g.other', 'S7-200 link', 6);

  // Errors from any plcwire node.
  row();
  nodes.push({ id: 'catch', type: 'catch', name: 'plcwire errors', scope: null, uncaught: false, ...at(160), wires: [['debug']] });
  nodes.push({ id: 'debug', type: 'debug', name: 'errors', active: true, tosidebar: true, console: false, complete: 'error', targetType: 'msg', ...at(360), wires: [] });

  return nodes;
}

/** The demo plant's default URLs (`npx plcwire demo`). */
const DEMO_URLS = Object.freeze({
  s7: 's7://127.0.0.1:10102?rack=0&slot=1',
  fetchwrite: 'fetchwrite://127.0.0.1?fetchPort=12000&writePort=12001',
  freeport: 'freeport+tcp://127.0.0.1:14001',
});

module.exports = { demoFlow, DEMO_URLS };

// `node demo/flows.js` regenerates the Dashboard 2 example from this flow.
if (require.main === module) {
  const fs = require('node:fs');
  const path = require('node:path');
  const dir = path.join(__dirname, '..', 'examples', 'Dashboard 2');
  fs.mkdirSync(dir, { recursive: true });
  fs.writeFileSync(path.join(dir, 'Plant dashboard for all three protocols.json'), `${JSON.stringify(demoFlow(DEMO_URLS), null, 2)}\n`);
}
