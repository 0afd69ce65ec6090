'use strict';
/**
 * The S7-1200's optimized DB "Tank" over S7CommPlus (demo/flows.js): a read
 * node polls its members by name, browsed from the PLC (the connection holds
 * no source file: the block has no offsets to compile), and the setpoint
 * slider writes "Tank".Setpoint by name. The connection's URL is pinned by
 * the certificate's fingerprint (the simulator makes its certificate at
 * start and the plant knows it); an imported copy of the flow has none: the
 * connection dialog's Get certificate pins it.
 */
const n = require('./flow-nodes');

const { X, at } = n;

/** The members polled, by name; a struct and an array whole. */
const PLUS_TAGS = [
  { name: 'phase', address: '"Tank".Phase' },
  { name: 'setpoint', address: '"Tank".Setpoint' },
  { name: 'drive', address: '"Tank".Drive' },
  { name: 'levels', address: '"Tank".Levels' },
];
const PLUS_WIDGETS = ['ui.plus.phase', 'ui.plus.setpoint', 'ui.plus.drive', 'ui.plus.levels'];

/**
 * The operator's setpoint: the slider shows "Tank".Setpoint as polled (passthru off: never written back),
 * and its text field or a release of its thumb writes the new value by name.
 */
const setpointSlider = (y) => ({
  id: 'ui.plus.setpoint',
  type: 'ui-slider',
  group: 'ui.g.plus',
  name: 'Setpoint',
  label: 'Temperature setpoint °C',
  tooltip: '',
  order: 2,
  width: 6,
  height: 1,
  passthru: false,
  outs: 'end',
  topic: '"Tank".Setpoint',
  topicType: 'str',
  thumbLabel: 'true',
  showTicks: 'false',
  min: 30,
  max: 60,
  step: 0.5,
  className: 'plcwire-setpoint',
  iconPrepend: '',
  iconAppend: '',
  color: '',
  colorTrack: '',
  colorThumb: '',
  showTextField: true,
  ...at(X.shape, y),
  wires: [['plus.write']],
});

/** "Tank".Drive, a struct read whole: its BOOL a lamp, its speed and current beside it. */
const DRIVE = `<div class="plcwire-lamp-row">
  <span>Feed drive</span>
  <span class="plcwire-lamp-text">{{ msg.payload ? msg.payload.Speed + ' rpm · ' + msg.payload.Current.toFixed(1) + ' A' : '' }}</span>
  <span class="plcwire-lamp" :class="msg.payload && msg.payload.Running === true ? 'plcwire-lamp-on' : 'plcwire-lamp-off'"></span>
</div>`;

/** "Tank".Levels, an ARRAY[0..4] OF REAL read whole, newest first. */
const LEVELS = `<div class="plcwire-lamp-row">
  <span>Level, last 5 s (%)</span>
  <span class="plcwire-lamp-text">{{ Array.isArray(msg.payload) ? msg.payload.map((v) => v.toFixed(1)).join(' · ') : '' }}</span>
</div>`;

/** The connection: S7CommPlus over TLS to the S7-1200's PUT/GET port, trusted by its certificate's fingerprint. */
function plusConnection(url) {
  return { id: 'conn.plus', type: 'plcwire-connection', name: 'S7-1200 S7CommPlus sim', url };
}

/** The panel: poll by name, route by tag, the widgets, the link lamp and the watchdog. */
function plusPanel(top) {
  const row = n.rows(top);
  return [
    n.read('plus.read', 'poll "Tank"', 'conn.plus', 1000, PLUS_TAGS, row(1), ['plus.route', 'plus.watch']),
    n.route(
      'plus.route',
      PLUS_TAGS.map((t) => t.name),
      row(1),
      [['ui.plus.phase'], ['ui.plus.setpoint'], ['ui.plus.drive'], ['ui.plus.levels']],
    ),
    n.text('ui.plus.phase', 'ui.g.plus', 'Phase', 1, 6, row(0)),
    setpointSlider(row(1)),
    {
      id: 'plus.write',
      type: 'plcwire-write',
      name: 'write setpoint',
      connection: 'conn.plus',
      tags: [],
      ...at(X.widget, row(1)),
      wires: [[]],
    },
    // Half a row more below the write node, for its status.
    n.template('ui.plus.drive', 'ui.g.plus', 'Feed drive', 3, 6, row(2.5), DRIVE),
    n.template('ui.plus.levels', 'ui.g.plus', 'Level history', 4, 6, row(3.5), LEVELS),
    // As wide as the group, as the rows above: its lamp under theirs.
    ...n.linkLamp('plus', 'S7CommPlus link', 'plus.read', 'ui.g.plus', 5, row(4.5), 'TLS link', 6),
    ...n.watchdog('plus', 3, row(5.5), PLUS_WIDGETS),
  ];
}

module.exports = { PLUS_TAGS, plusConnection, plusPanel };
