'use strict';
/**
 * The demo flow's parts (demo/flows.js), each a list of nodes: the dashboard's
 * page, the connections, a panel per PLC, the CPU panel, errors and the CSS.
 * A panel's rows start at the `top` it is given (see `rows`).
 */
const fs = require('node:fs');
const path = require('node:path');
const n = require('./flow-nodes');

const { X, at } = n;

/** Dashboard CSS for the lamps, the CPU panel and stale values (a site-wide ui-template style). */
const STYLE = fs.readFileSync(path.join(__dirname, 'dashboard.css'), 'utf8');

/** The tab and the two comments at its top. */
function intro() {
  return [
    { id: n.TAB, type: 'tab', label: 'plcwire demo', info: 'Simulated PLCs started by `npm start`.' },
    {
      id: 'demo.comment',
      type: 'comment',
      name: 'Simulators: npm start (S7 + S7CommPlus 10102, FETCH/WRITE 12000/12001, freeport 14001)',
      info: 'Run `npx plcwire demo` to start the same simulated plant without Node-RED.\n\nThe S7 and CP connections hold the source of the plant\'s DB1 (`Plant.db`, as TIA Portal generates it): their nodes read and write by name, `"Plant".Level`. Open a connection node to see its blocks.\n\nThe S7CommPlus connection reads the S7-1200\'s optimized DB `"Tank"` by name with no source file: the names come from the PLC (*Browse PLC* in the connection dialog lists them). It speaks TLS, trusting the simulator\'s certificate by its fingerprint in the URL; the simulator makes its certificate on its first start and keeps it for you (`npm start` and `npx plcwire demo` alike), so in a copy of this flow press *Get certificate* and *Pin* in the connection dialog once.',
      ...at(380, 40),
    },
    {
      id: 'demo.comment.dashboard',
      type: 'comment',
      name: 'Needs @flowfuse/node-red-dashboard (Dashboard 2.0); page at /dashboard/plant',
      info: "Install Dashboard 2.0 from the palette manager: @flowfuse/node-red-dashboard.\n\nBOOLs are lamps (ui-template); a watchdog (trigger) per link greys out that link's widgets through `msg.class` when no value arrived for a few polls.",
      ...at(340, 90),
    },
  ];
}

/** Dashboard 2.0 skeleton: one page of 12 columns, a group per PLC. */
function dashboard() {
  return [
    {
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
    },
    {
      id: 'ui.theme',
      type: 'ui-theme',
      name: 'plcwire',
      colors: { surface: '#1f3a5f', primary: '#0d74ce', bgPage: '#f9f9fb', groupBg: '#ffffff', groupOutline: '#d9d9e0' },
      sizes: { density: 'default', pagePadding: '12px', groupGap: '12px', groupBorderRadius: '4px', widgetGap: '12px' },
    },
    {
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
    },
    n.group('ui.g.s7', 'S7-1200 (S7comm)', 1, 6),
    n.group('ui.g.cpu', 'S7-1200 CPU', 2, 6),
    n.group('ui.g.fw', 'CP (FETCH/WRITE)', 3, 3),
    n.group('ui.g.fp', 'S7-200 (freeport)', 4, 3),
    n.group('ui.g.plus', 'S7-1200 optimized DB "Tank" over S7CommPlus (TLS)', 5, 6),
  ];
}

/**
 * Connections: one per PLC, shared by every node below.
 * control=true: the CPU panel's Stop and Start buttons may stop and restart the CPU.
 * The S7 and CP connections hold DB1's source (`symbols`): their nodes name the tags as the PLC program does.
 * @param {{ s7: string, fetchwrite: string, freeport: string }} urls
 * @param {() => object} symbols
 */
function connections(urls, symbols) {
  return [
    {
      id: 'conn.s7',
      type: 'plcwire-connection',
      name: 'S7-1200 sim',
      url: `${urls.s7}${urls.s7.includes('?') ? '&' : '?'}control=true`,
      // The dialog's CPU preset (rack 0, slot 1: what the URL says).
      cpu: 's7-1200',
      ...symbols(),
    },
    { id: 'conn.fw', type: 'plcwire-connection', name: 'CP fetch/write sim', url: urls.fetchwrite, ...symbols() },
    { id: 'conn.fp', type: 'plcwire-connection', name: 'S7-200 freeport sim', url: urls.freeport },
  ];
}

const S7_TAGS = [
  { name: 'level', address: '"Plant".Level' },
  { name: 'temperature', address: '"Plant".Temperature' },
  { name: 'run', address: '"Plant".MotorRun' },
  { name: 'running', address: '"Plant".MotorRunning' },
  { name: 'speed', address: '"Plant".MotorSpeed' },
  { name: 'parts', address: '"Plant".Parts' },
  { name: 'heater', address: '"Plant".Heater' },
];
const S7_WIDGETS = ['ui.level', 'ui.chart', 'ui.temp', 'ui.motor', 'ui.running', 'ui.speed', 'ui.parts', 'ui.heater'];

/** The chart of level and temperature over the last two minutes. */
const chart = (y) => ({
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
  ...at(X.widget, y),
  wires: [],
});

/**
 * The operator's switch: a click sends the run command to the PLC (passthru off, so the polled
 * bit coming in is not written back), and the switch shows the bit as polled (decouple: the
 * indicator follows the input), so it moves when anything else sets or clears "Plant".MotorRun (DB1.DBX4.0).
 */
const motorSwitch = (y) => ({
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
  ...at(X.shape, y),
  wires: [['s7.write']],
});

/** Our counter to "Plant".PcHeartbeat; the PLC's "Plant".PlcHeartbeat must keep changing. */
const heartbeat = (y) => [
  {
    id: 's7.heartbeat',
    type: 'plcwire-heartbeat',
    name: 'S7 life sign',
    connection: 'conn.s7',
    writeAddress: '"Plant".PcHeartbeat',
    writeMode: 'counter',
    interval: 1000,
    watchAddress: '"Plant".PlcHeartbeat',
    timeout: 3000,
    ...at(X.source, y),
    wires: [['s7.hbtext']],
  },
  n.change(
    's7.hbtext',
    'event to lamp',
    [
      { t: 'set', p: 'lamp', pt: 'msg', to: "payload.state = 'alive' ? 'green' : 'red'", tot: 'jsonata' },
      { t: 'set', p: 'payload', pt: 'msg', to: 'payload.event', tot: 'msg' },
    ],
    X.route,
    y,
    ['ui.heartbeat'],
  ),
  n.stateLamp('ui.heartbeat', 'ui.g.s7', 'PLC heartbeat', 10, 3, y),
];

/** S7: poll the process, one message per tag, routed by topic; widgets one under the other; the motor switch and the heartbeat. */
function s7Panel(top) {
  const row = n.rows(top);
  return [
    n.read('s7.read', 'poll S7', 'conn.s7', 500, S7_TAGS, row(3), ['s7.route', 's7.watch']),
    n.route(
      's7.route',
      S7_TAGS.map((t) => t.name),
      row(3),
      [['s7.round.level'], ['s7.round.temp'], ['ui.motor'], ['ui.running'], ['ui.speed'], ['ui.parts'], ['ui.heater']],
    ),
    n.round('s7.round.level', row(0), ['ui.level', 'ui.chart']),
    n.round('s7.round.temp', row(2), ['ui.temp', 'ui.chart']),
    n.gauge(
      'ui.level',
      'Tank level',
      1,
      '%',
      100,
      [
        { from: 0, color: '#5cd65c' },
        { from: 80, color: '#ffc800' },
        { from: 90, color: '#ea5353' },
      ],
      'plcwire-level',
      row(0),
    ),
    chart(row(1)),
    n.gauge(
      'ui.temp',
      'Temperature',
      2,
      '°C',
      80,
      [
        { from: 0, color: '#4a90d9' },
        { from: 30, color: '#5cd65c' },
        { from: 55, color: '#ffc800' },
        { from: 65, color: '#ea5353' },
      ],
      'plcwire-temp',
      row(2),
    ),
    motorSwitch(row(3)),
    { id: 's7.write', type: 'plcwire-write', name: 'write motor', connection: 'conn.s7', tags: [], ...at(X.widget, row(3)), wires: [[]] },
    // Half a row more below the write node, for its status.
    n.boolLamp('ui.running', 'ui.g.s7', 'Motor running', 5, 3, row(4.5)),
    n.text('ui.speed', 'ui.g.s7', 'Speed (rpm)', 6, 3, row(5.5)),
    n.text('ui.parts', 'ui.g.s7', 'Parts', 7, 3, row(6.5)),
    n.boolLamp('ui.heater', 'ui.g.s7', 'Heater on', 8, 6, row(7.5)),
    ...n.linkLamp('s7', 'S7 link', 's7.read', 'ui.g.s7', 9, row(8.5)),
    ...heartbeat(row(9.5)),
    // Below the rows the widgets are wired from, so its marks fan out upwards across no node.
    ...n.watchdog('s7', 2, row(11), S7_WIDGETS),
  ];
}

/**
 * The panel of a PLC read through one connection (`conn.<prefix>`, group `ui.g.<prefix>`): its level and
 * parts as text, its link lamp and its watchdog.
 * @param {string} prefix  `fw`, `fp`
 * @param {{ poll: string, link: string, tags: { name: string, address: string }[] }} plc
 * @param {number} top
 */
function linkPanel(prefix, plc, top) {
  const row = n.rows(top);
  const g = `ui.g.${prefix}`;
  return [
    n.read(`${prefix}.read`, plc.poll, `conn.${prefix}`, 1000, plc.tags, row(0), [`${prefix}.route`, `${prefix}.watch`]),
    n.route(`${prefix}.route`, ['level', 'parts'], row(0), [[`${prefix}.round`], [`ui.${prefix}.parts`]]),
    n.round(`${prefix}.round`, row(0), [`ui.${prefix}.level`]),
    n.text(`ui.${prefix}.level`, g, 'Tank level (%)', 1, 3, row(0)),
    n.text(`ui.${prefix}.parts`, g, 'Parts', 2, 3, row(1)),
    ...n.linkLamp(prefix, plc.link, `${prefix}.read`, g, 3, row(2)),
    ...n.watchdog(prefix, 3, row(3), [`ui.${prefix}.level`, `ui.${prefix}.parts`]),
  ];
}

/** Errors from any plcwire node to the debug sidebar, and the dashboard's CSS. */
function errorsAndStyle(top) {
  return [
    { id: 'catch', type: 'catch', name: 'plcwire errors', scope: null, uncaught: false, ...at(X.source, top), wires: [['debug']] },
    {
      id: 'debug',
      type: 'debug',
      name: 'errors',
      active: true,
      tosidebar: true,
      console: false,
      complete: 'error',
      targetType: 'msg',
      ...at(X.route, top),
      wires: [],
    },
    {
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
      ...at(X.widget, top),
      wires: [[]],
    },
  ];
}

module.exports = { STYLE, intro, dashboard, connections, s7Panel, linkPanel, errorsAndStyle };
