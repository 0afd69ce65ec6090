'use strict';
/**
 * Builders of the demo flow's nodes (demo/flows.js): each returns the node
 * objects of one kind, with the properties Node-RED's editor and Dashboard 2
 * write for it, placed on the demo's tab.
 */

/** The demo's one tab. */
const TAB = 'demo.tab';
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

/** A node's place on the tab. */
const at = (x, y) => ({ x, y, z: TAB });
/** The y of row `i` of a panel whose first row is at `top` (rows may be fractions). */
const rows = (top) => (i) => top + i * PITCH;
/** The class a widget carries, from its id (the browser test finds widgets by it). */
const cls = (id) => `plcwire-${id.replace(/\W/g, '-')}`;

/** Escapes text for a Vue template. */
function html(text) {
  return String(text).replace(/&/g, '&amp;').replace(/</g, '&lt;').replace(/>/g, '&gt;');
}

/** A Dashboard 2 group on the plant page. */
const group = (id, name, order, width) => ({
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

/** A value as text, label left and value right. */
const text = (id, g, label, order, width, y) => ({
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

/** A ui-template widget showing `format` (a Vue template). */
const template = (id, g, label, order, width, y, format, height = 1) => ({
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

/** A BOOL from the PLC: the lamp lights while msg.payload is true. */
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

/** A state: msg.lamp names the colour (green, yellow, red, grey), msg.payload the text beside it. */
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

/** A change node applying `rules`. */
const change = (id, name, rules, x, y, wires) => ({ id, type: 'change', name, rules, ...at(x, y), wires: [wires] });

/** Rounds msg.payload to one decimal. */
const round = (id, y, wires) =>
  change(id, 'one decimal', [{ t: 'set', p: 'payload', pt: 'msg', to: '$round(payload, 1)', tot: 'jsonata' }], X.shape, y, wires);

/** A function node running `func`; `wires` has one list per output. */
const fn = (id, name, func, outputs, x, y, wires) => ({
  id,
  type: 'function',
  name,
  func,
  outputs,
  timeout: 0,
  noerr: 0,
  initialize: '',
  finalize: '',
  libs: [],
  ...at(x, y),
  wires,
});

/** Routes a read node's per-tag messages by topic, one output per tag name. */
const route = (id, names, y, wires) => ({
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

/**
 * A link's watchdog: 'live' with the first value, 'stale' when none came for `seconds`; the mark
 * turns that into a class for the link's widgets (a message with only `class` keeps their value).
 */
const watchdog = (prefix, seconds, y, widgets) => [
  {
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
  },
  fn(`${prefix}.mark`, 'mark stale', `return { class: msg.payload === 'stale' ? '${STALE}' : '${LIVE}' };`, 1, X.shape, y, [widgets]),
];

/**
 * A link's state lamp `ui.link.<prefix>` from its read node's status: the lamp's colour is the status fill.
 * `name` labels the lamp and the status node, unless `short` names the status node (the editor's source column is narrow);
 * `width` is the widget's: the group's own width where the other rows span it, so the lamps line up at its right edge.
 */
const linkLamp = (prefix, name, readId, g, order, y, short = name, width = 3) => [
  { id: `st.${prefix}`, type: 'status', name: short, scope: [readId], ...at(X.source, y), wires: [[`st.text.${prefix}`]] },
  change(
    `st.text.${prefix}`,
    'status to lamp',
    [
      { t: 'set', p: 'payload', pt: 'msg', to: "$replace(status.text, 'plcwire.status.', '')", tot: 'jsonata' },
      { t: 'set', p: 'lamp', pt: 'msg', to: 'status.fill', tot: 'msg' },
    ],
    X.route,
    y,
    [`ui.link.${prefix}`],
  ),
  stateLamp(`ui.link.${prefix}`, g, name, order, width, y),
];

/** A plcwire read node polling `tags` every `interval` ms, one message per tag. */
const read = (id, name, connection, interval, tags, y, wires) => ({
  id,
  type: 'plcwire-read',
  name,
  connection,
  interval,
  output: 'per-tag',
  deadband: 0,
  tags,
  ...at(X.source, y),
  wires: [wires],
});

/** An inject sending the time every `repeat` seconds, once at the start too. */
const inject = (id, name, repeat, y, wires) => ({
  id,
  type: 'inject',
  name,
  props: [{ p: 'payload' }],
  repeat,
  crontab: '',
  once: true,
  onceDelay: '1',
  topic: '',
  payload: '',
  payloadType: 'date',
  ...at(X.inject, y),
  wires: [wires],
});

/** A plcwire control node on the S7 connection. */
const control = (id, name, action, y, wires) => ({
  id,
  type: 'plcwire-control',
  name,
  connection: 'conn.s7',
  action,
  newOnly: false,
  ...at(X.route, y),
  wires: [wires],
});

/** A half gauge 0 … `max` with coloured segments. */
const gauge = (id, title, order, units, max, segments, className, y) => ({
  id,
  type: 'ui-gauge',
  name: title,
  group: 'ui.g.s7',
  order,
  width: 3,
  height: 3,
  gtype: 'gauge-half',
  gstyle: 'needle',
  title,
  units,
  min: 0,
  max,
  segments,
  sizeThickness: 16,
  sizeGap: 4,
  sizeKeyThickness: 8,
  styleRounded: true,
  styleGlow: false,
  className,
  ...at(X.widget, y),
  wires: [],
});

/** A CPU panel button sending its action to the control node `cpu.<action>`. */
const cpuButton = (id, label, action, order, color, icon, y) => ({
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
  ...at(X.source, y),
  wires: [[`cpu.${action}`]],
});

module.exports = {
  TAB,
  X,
  PITCH,
  STALE,
  LIVE,
  at,
  rows,
  html,
  group,
  text,
  template,
  boolLamp,
  stateLamp,
  change,
  round,
  fn,
  route,
  watchdog,
  linkLamp,
  read,
  inject,
  control,
  gauge,
  cpuButton,
};
