'use strict';
/**
 * The demo flow deployed by `npm start`: for each protocol a connection, a
 * poll feeding a Dashboard 2.0 page, and for S7 a motor switch that writes the
 * run command and shows the PLC's copy of it, and a heartbeat. Generated here
 * (not a JSON blob) so the URLs follow the ports.
 *
 * What the page shows is what the PLC holds: BOOLs are lamps, the switch moves
 * when the bit changes in the PLC, and when a link delivers nothing for a few
 * polls (link down, PLC hung) a watchdog greys that link's widgets out
 * (Dashboard 2's `msg.class`) until values flow again.
 *
 * The S7-1200's CPU panel shows what the CPU says about itself (identity,
 * RUN/STOP, its clock, the diagnostic buffer) and has Stop and Start buttons:
 * the demo's S7 connection has `control=true`. In STOP the CPU still answers
 * reads but its program (the demo process) stands still, so the values freeze.
 *
 * The S7 and FETCH/WRITE connections carry the plant's DB1 as its PLC
 * programmer exports it (demo/Plant.db, TIA Portal's "Generate source from
 * blocks"), so every node there names its tags as TIA does ("Plant".Level);
 * the simulated PLCs are built from the same source (lib/plant/source.ts).
 * Freeport stations have no data blocks: they keep their addresses.
 */
const fs = require('node:fs');
const path = require('node:path');

/** The demo plant's DB1 source as a connection node keeps it (the file's text: its BOM and CRLFs are TIA's, not the source's). */
const PLANT_SOURCE = Object.freeze({
  name: 'Plant.db',
  content: fs
    .readFileSync(path.join(__dirname, 'Plant.db'), 'utf8')
    .replace(/^\uFEFF/, '')
    .replace(/\r\n/g, '\n'),
});
/** A TIA source does not carry its DB number: the connection node gives it. */
const PLANT_DB_NUMBERS = Object.freeze([{ block: 'Plant', db: 1 }]);

/**
 * Editor columns (node centres): sources (polls, status, heartbeat), routing
 * and watchdogs, shaping (rounding, stale marks, the switch), dashboard widgets.
 * The flow fits the editor's workspace of a 1280 px wide browser window.
 * An inject draws its button 25 px left of its body (editor-client view.js), so
 * the injects sit further right than the other sources: a 160 px wide "every
 * second" at 115 starts its button 10 px inside the canvas.
 */
const X = Object.freeze({ source: 90, inject: 115, route: 285, shape: 470, widget: 660 });
/** Vertical pitch of a column: a 30 px node and 10 px of air (nodes with a status get more, for its text). */
const PITCH = 40;
/** The class a watchdog puts on the widgets of a link that went quiet, and the one it restores. */
const STALE = 'plcwire-stale';
const LIVE = 'plcwire-live';

/** Dashboard CSS for the lamps, the CPU panel and stale values (a site-wide ui-template style). */
const STYLE = `/* plcwire demo: lamps for BOOLs and states, greyed-out widgets of a link that went quiet */
.plcwire-lamp-row { display: flex; align-items: center; justify-content: space-between; gap: 12px; width: 100%; min-height: 100%; font-size: 16px; }
.plcwire-lamp-text { margin-left: auto; font-weight: 600; }
.plcwire-lamp { flex: none; width: 20px; height: 20px; border-radius: 50%; border: 1px solid rgba(0, 0, 0, 0.35);
  background: radial-gradient(circle at 35% 30%, #f4f4f4, #a3a3a3 70%); box-shadow: inset 0 -2px 3px rgba(0, 0, 0, 0.2); }
.plcwire-lamp-on, .plcwire-lamp-green { background: radial-gradient(circle at 35% 30%, #c8f7c5, #1f9d2a 65%); box-shadow: 0 0 8px 2px rgba(31, 157, 42, 0.55); }
.plcwire-lamp-yellow { background: radial-gradient(circle at 35% 30%, #fff1b8, #e0a100 65%); box-shadow: 0 0 8px 2px rgba(224, 161, 0, 0.55); }
.plcwire-lamp-red { background: radial-gradient(circle at 35% 30%, #ffc9c9, #d32f2f 65%); box-shadow: 0 0 8px 2px rgba(211, 47, 47, 0.55); }
/* The CPU's identity: two columns (the long values left) on a wide card, one on a narrow one; a value wraps at its spaces, never clipped */
.plcwire-ui-cpu-identity { container-type: inline-size; }
.plcwire-cpu-identity { display: grid; grid-template-columns: minmax(0, 3fr) minmax(0, 2fr); gap: 6px 24px; width: 100%; font-size: 15px; }
@container (max-width: 480px) { .plcwire-cpu-identity { grid-template-columns: minmax(0, 1fr); } }
.plcwire-cpu-identity > div { display: flex; justify-content: space-between; align-items: baseline; gap: 12px; }
.plcwire-cpu-identity span { white-space: nowrap; }
.plcwire-cpu-identity b { min-width: 0; text-align: right; overflow-wrap: break-word; font-weight: 600; }
.plcwire-cpu-diag th, .plcwire-cpu-diag td:nth-child(-n+2) { white-space: nowrap; }
.plcwire-cpu-diag .v-table > .v-table__wrapper > table > tbody > tr > td { height: 36px; }
/* A narrow diagnostic table is stacked, a line per cell: the title as wide as it needs, the value the rest; the description
   under its title, the card's full width (no sort box: newest first) */
.plcwire-cpu-diag .nrdb-table--mobile thead { display: none; }
.plcwire-cpu-diag .nrdb-table--mobile .v-table__wrapper > table > tbody > tr > td { height: auto; min-height: 28px; grid-template-columns: auto minmax(0, 1fr); gap: 12px; }
.plcwire-cpu-diag .nrdb-table--mobile td > .nrdb-table-cell-align { text-align: right; }
.plcwire-cpu-diag .nrdb-table--mobile .v-table__wrapper > table > tbody > tr > td[data-column-key="description"] { grid-template-columns: minmax(0, 1fr); gap: 0; padding-bottom: 6px; }
.plcwire-cpu-diag .nrdb-table--mobile td[data-column-key="description"] > div:first-child { font-size: 12px; opacity: 0.7; }
.plcwire-cpu-diag .nrdb-table--mobile td[data-column-key="description"] > .nrdb-table-cell-align { justify-content: start !important; text-align: left; }
/* The motor switch's label in the text colour of the other widgets (Vuetify dims a v-label) */
.plcwire-motor .v-label { opacity: 1; color: inherit; }
.plcwire-cpu-diag .v-data-table-footer { display: none; }
.plcwire-stale { position: relative; opacity: 0.45; filter: grayscale(1); }
.plcwire-stale::after { content: 'stale'; position: absolute; top: -9px; right: 0; padding: 0 6px; border-radius: 8px;
  font-size: 11px; line-height: 16px; color: #fff; background: #6b6b6b; pointer-events: none; }
`;

/** Escapes text for a Vue template. */
function html(text) {
  return String(text).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;');
}

/** @param {{ s7: string, fetchwrite: string, freeport: string }} urls */
function demoFlow(urls) {
  const tab = 'demo.tab';
  const nodes = [];
  const at = (x, y) => ({ x, y, z: tab });

  nodes.push({ id: tab, type: 'tab', label: 'plcwire demo', info: 'Simulated PLCs started by `npm start`.' });
  nodes.push({
    id: 'demo.comment',
    type: 'comment',
    name: 'Simulators: started by npm start (S7 10102, FETCH/WRITE 12000/12001, freeport tcp 14001)',
    info: 'Run `npx plcwire demo` to start the same simulated plant without Node-RED.\n\nThe S7 and CP connections hold the source of the plant\'s DB1 (`Plant.db`, as TIA Portal generates it): their nodes read and write by name, `"Plant".Level`. Open a connection node to see its blocks.',
    ...at(380, 40),
  });
  nodes.push({
    id: 'demo.comment.dashboard',
    type: 'comment',
    name: 'Needs @flowfuse/node-red-dashboard (Dashboard 2.0); page at /dashboard/plant',
    info: "Install Dashboard 2.0 from the palette manager: @flowfuse/node-red-dashboard.\n\nBOOLs are lamps (ui-template); a watchdog (trigger) per link greys out that link's widgets through `msg.class` when no value arrived for a few polls.",
    ...at(340, 90),
  });

  // Dashboard 2.0 skeleton: one page of 12 columns, a group per PLC.
  nodes.push({
    id: 'ui.base',
    type: 'ui-base',
    name: 'plcwire',
    path: '/dashboard',
    includeClientData: true,
    acceptsClientConfig: ['ui-notification', 'ui-control'],
    showPathInSidebar: false,
    // No "App is offline ready" toast over the page: Dashboard 2 shows it only for an installable app
    // ("Allow App Installation", @flowfuse/node-red-dashboard nodes/config/ui_base.js, on by default).
    allowInstall: false,
    navigationStyle: 'none',
    titleBarStyle: 'default',
  });
  nodes.push({
    id: 'ui.theme',
    type: 'ui-theme',
    name: 'plcwire',
    colors: { surface: '#1f3a5f', primary: '#0d74ce', bgPage: '#f9f9fb', groupBg: '#ffffff', groupOutline: '#d9d9e0' },
    sizes: { density: 'default', pagePadding: '12px', groupGap: '12px', groupBorderRadius: '4px', widgetGap: '12px' },
  });
  nodes.push({
    id: 'ui.page',
    type: 'ui-page',
    name: 'Plant',
    ui: 'ui.base',
    path: '/plant',
    icon: 'factory',
    layout: 'grid',
    theme: 'ui.theme',
    order: 1,
    visible: 'true',
    disabled: 'false',
    breakpoints: [
      { name: 'Default', px: 0, cols: 3 },
      { name: 'Tablet', px: 576, cols: 6 },
      { name: 'Small Desktop', px: 768, cols: 9 },
      { name: 'Desktop', px: 1024, cols: 12 },
    ],
  });
  const group = (id, name, order, width) =>
    nodes.push({
      id,
      type: 'ui-group',
      name,
      page: 'ui.page',
      width,
      height: 1,
      order,
      showTitle: true,
      visible: 'true',
      disabled: 'false',
      groupType: 'default',
    });
  group('ui.g.s7', 'S7-1200 (S7comm)', 1, 6);
  group('ui.g.cpu', 'S7-1200 CPU', 2, 6);
  group('ui.g.fw', 'CP (FETCH/WRITE)', 3, 3);
  group('ui.g.fp', 'S7-200 (freeport)', 4, 3);
  const cls = (id) => `plcwire-${id.replace(/\W/g, '-')}`;
  const text = (id, g, label, order, width, y) =>
    nodes.push({
      id,
      type: 'ui-text',
      group: g,
      order,
      width,
      height: 1,
      name: label,
      label,
      format: '{{msg.payload}}',
      layout: 'row-spread',
      style: false,
      value: 'payload',
      valueType: 'msg',
      className: cls(id),
      ...at(X.widget, y),
      wires: [],
    });
  const template = (id, g, label, order, width, y, format, height = 1) =>
    nodes.push({
      id,
      type: 'ui-template',
      group: g,
      page: '',
      ui: '',
      name: label,
      order,
      width,
      height,
      head: '',
      format,
      storeOutMessages: true,
      passthru: false,
      resendOnRefresh: true,
      templateScope: 'local',
      className: cls(id),
      ...at(X.widget, y),
      wires: [[]],
    });
  // A BOOL from the PLC: the lamp lights while msg.payload is true.
  const boolLamp = (id, g, label, order, width, y) =>
    template(
      id,
      g,
      label,
      order,
      width,
      y,
      `<div class="plcwire-lamp-row">
  <span>${html(label)}</span>
  <span class="plcwire-lamp" :class="msg.payload === true ? 'plcwire-lamp-on' : 'plcwire-lamp-off'" :title="msg.payload === true ? 'on' : 'off'"></span>
</div>`,
    );
  // A state: msg.lamp names the colour (green, yellow, red, grey), msg.payload the text beside it.
  const stateLamp = (id, g, label, order, width, y) =>
    template(
      id,
      g,
      label,
      order,
      width,
      y,
      `<div class="plcwire-lamp-row">
  <span>${html(label)}</span>
  <span class="plcwire-lamp-text">{{ msg.payload }}</span>
  <span class="plcwire-lamp" :class="'plcwire-lamp-' + (msg.lamp || 'grey')"></span>
</div>`,
    );
  const round = (id, y, wires) =>
    nodes.push({
      id,
      type: 'change',
      name: 'one decimal',
      rules: [{ t: 'set', p: 'payload', pt: 'msg', to: '$round(payload, 1)', tot: 'jsonata' }],
      ...at(X.shape, y),
      wires: [wires],
    });
  const route = (id, names, y, wires) =>
    nodes.push({
      id,
      type: 'switch',
      name: 'by tag',
      property: 'topic',
      propertyType: 'msg',
      checkall: 'false',
      outputs: names.length,
      rules: names.map((v) => ({ t: 'eq', v, vt: 'str' })),
      ...at(X.route, y),
      wires,
    });
  // A link's watchdog: 'live' with the first value, 'stale' when none came for `seconds`; the mark
  // turns that into a class for the link's widgets (a message with only `class` keeps their value).
  const watchdog = (prefix, seconds, y, widgets) => {
    nodes.push({
      id: `${prefix}.watch`,
      type: 'trigger',
      name: `watchdog ${seconds} s`,
      op1: 'live',
      op2: 'stale',
      op1type: 'str',
      op2type: 'str',
      duration: String(seconds),
      extend: true,
      overrideDelay: false,
      units: 's',
      reset: '',
      bytopic: 'all',
      topic: 'topic',
      outputs: 1,
      ...at(X.route, y),
      wires: [[`${prefix}.mark`]],
    });
    nodes.push({
      id: `${prefix}.mark`,
      type: 'function',
      name: 'mark stale',
      func: `return { class: msg.payload === 'stale' ? '${STALE}' : '${LIVE}' };`,
      outputs: 1,
      timeout: 0,
      noerr: 0,
      initialize: '',
      finalize: '',
      libs: [],
      ...at(X.shape, y),
      wires: [widgets],
    });
  };
  // A link's state from its read node's status: the lamp's colour is the status fill.
  const linkState = (prefix, name, readId, y, widget) => {
    nodes.push({ id: `st.${prefix}`, type: 'status', name, scope: [readId], ...at(X.source, y), wires: [[`st.text.${prefix}`]] });
    nodes.push({
      id: `st.text.${prefix}`,
      type: 'change',
      name: 'status to lamp',
      rules: [
        { t: 'set', p: 'payload', pt: 'msg', to: "$replace(status.text, 'plcwire.status.', '')", tot: 'jsonata' },
        { t: 'set', p: 'lamp', pt: 'msg', to: 'status.fill', tot: 'msg' },
      ],
      ...at(X.route, y),
      wires: [[widget]],
    });
  };

  // Connections: one per PLC, shared by every node below.
  // control=true: the CPU panel's Stop and Start buttons may stop and restart the CPU.
  // The S7 and CP connections hold DB1's source: their nodes name the tags as the PLC program does.
  const symbols = () => ({ symbolSources: [{ ...PLANT_SOURCE }], dbNumbers: PLANT_DB_NUMBERS.map((d) => ({ ...d })) });
  nodes.push({
    id: 'conn.s7',
    type: 'plcwire-connection',
    name: 'S7-1200 sim',
    url: `${urls.s7}${urls.s7.includes('?') ? '&' : '?'}control=true`,
    // The dialog's CPU preset (rack 0, slot 1: what the URL says).
    cpu: 's7-1200',
    ...symbols(),
  });
  nodes.push({ id: 'conn.fw', type: 'plcwire-connection', name: 'CP fetch/write sim', url: urls.fetchwrite, ...symbols() });
  nodes.push({ id: 'conn.fp', type: 'plcwire-connection', name: 'S7-200 freeport sim', url: urls.freeport });

  // S7: poll the process, one message per tag, routed by topic; widgets one under the other.
  let y = 140;
  const row = (i) => y + i * PITCH;
  const s7Tags = [
    { name: 'level', address: '"Plant".Level' },
    { name: 'temperature', address: '"Plant".Temperature' },
    { name: 'run', address: '"Plant".MotorRun' },
    { name: 'running', address: '"Plant".MotorRunning' },
    { name: 'speed', address: '"Plant".MotorSpeed' },
    { name: 'parts', address: '"Plant".Parts' },
    { name: 'heater', address: '"Plant".Heater' },
  ];
  const s7Widgets = ['ui.level', 'ui.chart', 'ui.temp', 'ui.motor', 'ui.running', 'ui.speed', 'ui.parts', 'ui.heater'];
  nodes.push({
    id: 's7.read',
    type: 'plcwire-read',
    name: 'poll S7',
    connection: 'conn.s7',
    interval: 500,
    output: 'per-tag',
    deadband: 0,
    tags: s7Tags,
    ...at(X.source, row(3)),
    wires: [['s7.route', 's7.watch']],
  });
  route(
    's7.route',
    s7Tags.map((t) => t.name),
    row(3),
    [['s7.round.level'], ['s7.round.temp'], ['ui.motor'], ['ui.running'], ['ui.speed'], ['ui.parts'], ['ui.heater']],
  );
  round('s7.round.level', row(0), ['ui.level', 'ui.chart']);
  round('s7.round.temp', row(2), ['ui.temp', 'ui.chart']);
  nodes.push({
    id: 'ui.level',
    type: 'ui-gauge',
    name: 'Tank level',
    group: 'ui.g.s7',
    order: 1,
    width: 3,
    height: 3,
    gtype: 'gauge-half',
    gstyle: 'needle',
    title: 'Tank level',
    units: '%',
    min: 0,
    max: 100,
    segments: [
      { from: 0, color: '#5cd65c' },
      { from: 80, color: '#ffc800' },
      { from: 90, color: '#ea5353' },
    ],
    sizeThickness: 16,
    sizeGap: 4,
    sizeKeyThickness: 8,
    styleRounded: true,
    styleGlow: false,
    className: 'plcwire-level',
    ...at(X.widget, row(0)),
    wires: [],
  });
  nodes.push({
    id: 'ui.chart',
    type: 'ui-chart',
    name: 'Level and temp',
    group: 'ui.g.s7',
    order: 3,
    width: 6,
    height: 4,
    label: 'Level % and temperature °C (last 2 min)',
    chartType: 'line',
    category: 'topic',
    categoryType: 'msg',
    xAxisType: 'time',
    xAxisPropertyType: 'timestamp',
    yAxisProperty: 'payload',
    yAxisPropertyType: 'msg',
    action: 'append',
    removeOlder: 2,
    removeOlderUnit: '60',
    removeOlderPoints: '',
    showLegend: true,
    pointShape: 'circle',
    pointRadius: 2,
    interpolation: 'linear',
    colors: ['#0095FF', '#FF7F0E'],
    className: 'plcwire-chart',
    ...at(X.widget, row(1)),
    wires: [],
  });
  nodes.push({
    id: 'ui.temp',
    type: 'ui-gauge',
    name: 'Temperature',
    group: 'ui.g.s7',
    order: 2,
    width: 3,
    height: 3,
    gtype: 'gauge-half',
    gstyle: 'needle',
    title: 'Temperature',
    units: '°C',
    min: 0,
    max: 80,
    segments: [
      { from: 0, color: '#4a90d9' },
      { from: 30, color: '#5cd65c' },
      { from: 55, color: '#ffc800' },
      { from: 65, color: '#ea5353' },
    ],
    sizeThickness: 16,
    sizeGap: 4,
    sizeKeyThickness: 8,
    styleRounded: true,
    styleGlow: false,
    className: 'plcwire-temp',
    ...at(X.widget, row(2)),
    wires: [],
  });
  // The operator's switch: a click sends the run command to the PLC (passthru off, so the polled
  // bit coming in is not written back), and the switch shows the bit as polled (decouple: the
  // indicator follows the input), so it moves when anything else sets or clears "Plant".MotorRun (DB1.DBX4.0).
  nodes.push({
    id: 'ui.motor',
    type: 'ui-switch',
    name: 'Motor run',
    label: 'Motor run',
    group: 'ui.g.s7',
    order: 4,
    width: 3,
    height: 1,
    passthru: false,
    decouple: true,
    topic: '"Plant".MotorRun',
    topicType: 'str',
    style: '',
    className: 'plcwire-motor',
    layout: 'row-spread',
    clickableArea: 'switch',
    onvalue: true,
    onvalueType: 'bool',
    onicon: '',
    oncolor: '',
    offvalue: false,
    offvalueType: 'bool',
    officon: '',
    offcolor: '',
    ...at(X.shape, row(3)),
    wires: [['s7.write']],
  });
  nodes.push({
    id: 's7.write',
    type: 'plcwire-write',
    name: 'write motor',
    connection: 'conn.s7',
    tags: [],
    ...at(X.widget, row(3)),
    wires: [[]],
  });
  // Half a row more below the write node, for its status.
  boolLamp('ui.running', 'ui.g.s7', 'Motor running', 5, 3, row(4.5));
  text('ui.speed', 'ui.g.s7', 'Speed (rpm)', 6, 3, row(5.5));
  text('ui.parts', 'ui.g.s7', 'Parts', 7, 3, row(6.5));
  boolLamp('ui.heater', 'ui.g.s7', 'Heater on', 8, 6, row(7.5));
  linkState('s7', 'S7 link', 's7.read', row(8.5), 'ui.link.s7');
  stateLamp('ui.link.s7', 'ui.g.s7', 'S7 link', 9, 3, row(8.5));

  // S7: heartbeat — our counter to "Plant".PcHeartbeat, the PLC's "Plant".PlcHeartbeat must keep changing.
  nodes.push({
    id: 's7.heartbeat',
    type: 'plcwire-heartbeat',
    name: 'S7 life sign',
    connection: 'conn.s7',
    writeAddress: '"Plant".PcHeartbeat',
    writeMode: 'counter',
    interval: 1000,
    watchAddress: '"Plant".PlcHeartbeat',
    timeout: 3000,
    ...at(X.source, row(9.5)),
    wires: [['s7.hbtext']],
  });
  nodes.push({
    id: 's7.hbtext',
    type: 'change',
    name: 'event to lamp',
    rules: [
      { t: 'set', p: 'lamp', pt: 'msg', to: "payload.state = 'alive' ? 'green' : 'red'", tot: 'jsonata' },
      { t: 'set', p: 'payload', pt: 'msg', to: 'payload.event', tot: 'msg' },
    ],
    ...at(X.route, row(9.5)),
    wires: [['ui.heartbeat']],
  });
  stateLamp('ui.heartbeat', 'ui.g.s7', 'PLC heartbeat', 10, 3, row(9.5));
  // Below the rows the widgets are wired from, so its marks fan out upwards across no node.
  watchdog('s7', 2, row(11), s7Widgets);

  // The S7-1200's CPU: state, clock and diagnostic buffer every second, identity every 10 s,
  // Stop and Start buttons; a watchdog greys the panel when the state stops coming.
  y = row(13);
  const control = (id, name, action, r, wires) =>
    nodes.push({
      id,
      type: 'plcwire-control',
      name,
      connection: 'conn.s7',
      action,
      newOnly: false,
      ...at(X.route, row(r)),
      wires: [wires],
    });
  const cpuWidgets = ['ui.cpu.state', 'ui.cpu.clock', 'ui.cpu.identity'];
  nodes.push({
    id: 'cpu.poll',
    type: 'inject',
    name: 'every second',
    props: [{ p: 'payload' }],
    repeat: '1',
    crontab: '',
    once: true,
    onceDelay: '1',
    topic: '',
    payload: '',
    payloadType: 'date',
    ...at(X.inject, row(0)),
    wires: [['cpu.state', 'cpu.clock', 'cpu.diag']],
  });
  control('cpu.state', 'CPU state', 'state', 0, ['cpu.lamp', 'cpu.watch', 'cpu.buttons']);
  // state and stop/start answer { state: 'run' | 'stop' | … }.
  nodes.push({
    id: 'cpu.lamp',
    type: 'change',
    name: 'state to lamp',
    rules: [
      { t: 'set', p: 'lamp', pt: 'msg', to: "payload.state = 'run' ? 'green' : payload.state = 'stop' ? 'red' : 'yellow'", tot: 'jsonata' },
      { t: 'set', p: 'payload', pt: 'msg', to: '$uppercase(payload.state)', tot: 'jsonata' },
    ],
    ...at(X.shape, row(0)),
    wires: [['ui.cpu.state']],
  });
  stateLamp('ui.cpu.state', 'ui.g.cpu', 'CPU', 2, 3, row(0));
  control('cpu.clock', 'PLC clock', 'clock', 1.5, ['cpu.clocktext']);
  nodes.push({
    id: 'cpu.clocktext',
    type: 'change',
    name: 'date and time',
    rules: [{ t: 'set', p: 'payload', pt: 'msg', to: "$replace($substring(payload, 0, 19), 'T', ' ')", tot: 'jsonata' }],
    ...at(X.shape, row(1.5)),
    wires: [['ui.cpu.clock']],
  });
  text('ui.cpu.clock', 'ui.g.cpu', 'PLC clock', 3, 3, row(1.5));
  control('cpu.diag', 'diagnostics', 'diagnostics', 3, ['cpu.rows']);
  // The newest ten entries as table rows: the time to the millisecond, the event ID as the CPU's tools write it.
  nodes.push({
    id: 'cpu.rows',
    type: 'function',
    name: 'newest ten',
    func: `const hex = (n) => '16#' + n.toString(16).toUpperCase().padStart(4, '0');
msg.payload = msg.payload.slice(0, 10).map((e) => ({
  time: e.time ? e.time.slice(0, 23).replace('T', ' ') : '',
  event: hex(e.eventId),
  description: e.description || '',
}));
return msg;`,
    outputs: 1,
    timeout: 0,
    noerr: 0,
    initialize: '',
    finalize: '',
    libs: [],
    ...at(X.shape, row(3)),
    wires: [['ui.cpu.diag']],
  });
  nodes.push({
    id: 'ui.cpu.diag',
    type: 'ui-table',
    group: 'ui.g.cpu',
    name: 'Diagnostic buffer',
    label: 'Diagnostic buffer (newest first)',
    order: 6,
    width: 6,
    height: 0,
    maxrows: 10,
    passthru: false,
    autocols: false,
    showSearch: false,
    deselect: true,
    selectionType: 'none',
    columns: [
      { title: 'Time', key: 'time', keyType: 'key', type: 'text', width: '', align: 'start' },
      { title: 'Event', key: 'event', keyType: 'key', type: 'text', width: '', align: 'start' },
      { title: 'Description', key: 'description', keyType: 'key', type: 'text', width: '', align: 'start' },
    ],
    // Stacked (a row per cell, the description the card's width) when the table is 576 px wide or less. In
    // pixels: Dashboard 2 1.31's table looks "defaults: sm" (its editor's "Mobile (< 576px)") up among xs, md
    // and lg only (ui/src/widgets/ui-table/UITable.vue checkBreakpoint), so it never stacks.
    mobileBreakpoint: 576,
    mobileBreakpointType: 'px',
    action: 'replace',
    className: 'plcwire-cpu-diag',
    ...at(X.widget, row(3)),
    wires: [[]],
  });
  nodes.push({
    id: 'cpu.identify',
    type: 'inject',
    name: 'every 10 s',
    props: [{ p: 'payload' }],
    repeat: '10',
    crontab: '',
    once: true,
    onceDelay: '1',
    topic: '',
    payload: '',
    payloadType: 'date',
    ...at(X.inject, row(4.5)),
    wires: [['cpu.info']],
  });
  control('cpu.info', 'CPU identity', 'info', 4.5, ['ui.cpu.identity']);
  const field = (label, expr) => `  <div><span>${html(label)}</span><b>{{ ${expr} }}</b></div>`;
  template(
    'ui.cpu.identity',
    'ui.g.cpu',
    'CPU identity',
    1,
    6,
    row(4.5),
    [
      '<div class="plcwire-cpu-identity">',
      field('Module', '(msg.payload || {}).moduleTypeName'),
      field('Name', '(msg.payload || {}).moduleName'),
      field('Order code', '(msg.payload || {}).orderCode'),
      field('Firmware', '(msg.payload || {}).firmware'),
      field('Serial number', '(msg.payload || {}).serialNumber'),
      field('AS name', '(msg.payload || {}).asName'),
      '</div>',
    ].join('\n'),
    // Height 0: as tall as its fields, two columns of three on a wide card, one of six on a phone.
    0,
  );
  const cpuButton = (id, label, action, order, color, icon, r) =>
    nodes.push({
      id,
      type: 'ui-button',
      group: 'ui.g.cpu',
      name: label,
      label,
      order,
      width: 3,
      height: 1,
      emulateClick: false,
      tooltip: '',
      color: '',
      bgcolor: '',
      className: `plcwire-cpu-${action}`,
      icon,
      iconPosition: 'left',
      payload: '',
      payloadType: 'str',
      topic: action,
      topicType: 'str',
      buttonColor: color,
      textColor: '#ffffff',
      iconColor: '#ffffff',
      ...at(X.source, row(r)),
      wires: [[`cpu.${action}`]],
    });
  cpuButton('ui.cpu.stop', 'Stop CPU', 'stop', 4, '#d32f2f', 'stop', 6);
  control('cpu.stop', 'stop CPU', 'stop', 6, ['cpu.lamp', 'cpu.buttons']);
  cpuButton('ui.cpu.start', 'Start CPU', 'start', 5, '#1f9d2a', 'play', 7.5);
  control('cpu.start', 'start CPU', 'start', 7.5, ['cpu.lamp', 'cpu.buttons']);
  // Stop only in RUN, Start only in STOP (in any other state neither): Dashboard 2's msg.enabled, sent when
  // the state changes (a dashboard opened later gets it from Dashboard 2's state store).
  nodes.push({
    id: 'cpu.buttons',
    type: 'function',
    name: 'buttons per state',
    func: `const state = String((msg.payload || {}).state);
if (context.get('state') === state) return null;
context.set('state', state);
return [{ enabled: state === 'run' }, { enabled: state === 'stop' }];`,
    outputs: 2,
    timeout: 0,
    noerr: 0,
    initialize: '',
    finalize: '',
    libs: [],
    ...at(X.shape, row(6.75)),
    wires: [['ui.cpu.stop'], ['ui.cpu.start']],
  });
  watchdog('cpu', 3, row(9), cpuWidgets);

  // FETCH/WRITE: the same DB1 through the CP, by the same names (the CP serves the CPU's data blocks).
  y = row(11);
  nodes.push({
    id: 'fw.read',
    type: 'plcwire-read',
    name: 'poll CP',
    connection: 'conn.fw',
    interval: 1000,
    output: 'per-tag',
    deadband: 0,
    tags: [
      { name: 'level', address: '"Plant".Level' },
      { name: 'parts', address: '"Plant".Parts' },
    ],
    ...at(X.source, row(0)),
    wires: [['fw.route', 'fw.watch']],
  });
  route('fw.route', ['level', 'parts'], row(0), [['fw.round'], ['ui.fw.parts']]);
  round('fw.round', row(0), ['ui.fw.level']);
  text('ui.fw.level', 'ui.g.fw', 'Tank level (%)', 1, 3, row(0));
  text('ui.fw.parts', 'ui.g.fw', 'Parts', 2, 3, row(1));
  linkState('fw', 'CP link', 'fw.read', row(2), 'ui.link.fw');
  stateLamp('ui.link.fw', 'ui.g.fw', 'CP link', 3, 3, row(2));
  watchdog('fw', 3, row(3), ['ui.fw.level', 'ui.fw.parts']);

  // Freeport: stations 5 (level, REAL) and 6 (parts, DINT) on the RS-485 bus, through a serial device server.
  y = row(5);
  nodes.push({
    id: 'fp.read',
    type: 'plcwire-read',
    name: 'poll S7-200',
    connection: 'conn.fp',
    interval: 1000,
    output: 'per-tag',
    deadband: 0,
    tags: [
      { name: 'level', address: 'ST5,REAL0' },
      { name: 'parts', address: 'ST6,DINT0' },
    ],
    ...at(X.source, row(0)),
    wires: [['fp.route', 'fp.watch']],
  });
  route('fp.route', ['level', 'parts'], row(0), [['fp.round'], ['ui.fp.parts']]);
  round('fp.round', row(0), ['ui.fp.level']);
  text('ui.fp.level', 'ui.g.fp', 'Tank level (%)', 1, 3, row(0));
  text('ui.fp.parts', 'ui.g.fp', 'Parts', 2, 3, row(1));
  linkState('fp', 'S7-200 link', 'fp.read', row(2), 'ui.link.fp');
  stateLamp('ui.link.fp', 'ui.g.fp', 'S7-200 link', 3, 3, row(2));
  watchdog('fp', 3, row(3), ['ui.fp.level', 'ui.fp.parts']);

  // Errors from any plcwire node, and the dashboard's CSS.
  y = row(5);
  nodes.push({
    id: 'catch',
    type: 'catch',
    name: 'plcwire errors',
    scope: null,
    uncaught: false,
    ...at(X.source, row(0)),
    wires: [['debug']],
  });
  nodes.push({
    id: 'debug',
    type: 'debug',
    name: 'errors',
    active: true,
    tosidebar: true,
    console: false,
    complete: 'error',
    targetType: 'msg',
    ...at(X.route, row(0)),
    wires: [],
  });
  nodes.push({
    id: 'ui.style',
    type: 'ui-template',
    group: '',
    page: '',
    ui: 'ui.base',
    name: 'CSS: lamps, stale',
    order: 0,
    width: 0,
    height: 0,
    head: '',
    format: STYLE,
    storeOutMessages: true,
    passthru: true,
    resendOnRefresh: true,
    templateScope: 'site:style',
    className: '',
    ...at(X.widget, row(0)),
    wires: [[]],
  });

  return nodes;
}

/** The demo plant's default URLs (`npx plcwire demo`). */
const DEMO_URLS = Object.freeze({
  s7: 's7://127.0.0.1:10102?rack=0&slot=1',
  fetchwrite: 'fetchwrite://127.0.0.1?fetchPort=12000&writePort=12001',
  freeport: 'freeport+tcp://127.0.0.1:14001',
});

module.exports = { demoFlow, DEMO_URLS, PLANT_SOURCE, PLANT_DB_NUMBERS, STALE, LIVE };

// `node demo/flows.js` regenerates the Dashboard 2 example from this flow.
if (require.main === module) {
  const dir = path.join(__dirname, '..', 'examples', 'Dashboard 2');
  fs.mkdirSync(dir, { recursive: true });
  fs.writeFileSync(path.join(dir, 'Plant dashboard for all three protocols.json'), `${JSON.stringify(demoFlow(DEMO_URLS), null, 2)}\n`);
}
