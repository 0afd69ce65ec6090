'use strict';
/**
 * The S7-1200's CPU panel of the demo flow (demo/flows.js): state, clock and
 * diagnostic buffer every second, identity every 10 s, Stop and Start buttons;
 * a watchdog greys the panel when the state stops coming.
 */
const n = require('./flow-nodes');

const { X, at, html } = n;

const CPU_WIDGETS = ['ui.cpu.state', 'ui.cpu.clock', 'ui.cpu.identity'];

// state and stop/start answer { state: 'run' | 'stop' | … }.
const stateToLamp = (y) =>
  n.change(
    'cpu.lamp',
    'state to lamp',
    [
      { t: 'set', p: 'lamp', pt: 'msg', to: "payload.state = 'run' ? 'green' : payload.state = 'stop' ? 'red' : 'yellow'", tot: 'jsonata' },
      { t: 'set', p: 'payload', pt: 'msg', to: '$uppercase(payload.state)', tot: 'jsonata' },
    ],
    X.shape,
    y,
    ['ui.cpu.state'],
  );

/** The newest ten entries as table rows: the time to the millisecond, the event ID as the CPU's tools write it. */
const NEWEST_TEN = `const hex = (n) => '16#' + n.toString(16).toUpperCase().padStart(4, '0');
msg.payload = msg.payload.slice(0, 10).map((e) => ({
  time: e.time ? e.time.slice(0, 23).replace('T', ' ') : '',
  event: hex(e.eventId),
  description: e.description || '',
}));
return msg;`;

/**
 * Stop only in RUN, Start only in STOP (in any other state neither): Dashboard 2's msg.enabled, sent when
 * the state changes (a dashboard opened later gets it from Dashboard 2's state store).
 */
const BUTTONS_PER_STATE = `const state = String((msg.payload || {}).state);
if (context.get('state') === state) return null;
context.set('state', state);
return [{ enabled: state === 'run' }, { enabled: state === 'stop' }];`;

const column = (title, key) => ({ title, key, keyType: 'key', type: 'text', width: '', align: 'start' });

const diagnosticTable = (y) => ({
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
  columns: [column('Time', 'time'), column('Event', 'event'), column('Description', 'description')],
  // Stacked (a row per cell, the description the card's width) when the table is 576 px wide or less. In
  // pixels: Dashboard 2 1.31's table looks "defaults: sm" (its editor's "Mobile (< 576px)") up among xs, md
  // and lg only (ui/src/widgets/ui-table/UITable.vue checkBreakpoint), so it never stacks.
  mobileBreakpoint: 576,
  mobileBreakpointType: 'px',
  action: 'replace',
  className: 'plcwire-cpu-diag',
  ...at(X.widget, y),
  wires: [[]],
});

const field = (label, expr) => `  <div><span>${html(label)}</span><b>{{ ${expr} }}</b></div>`;

const identity = (y) =>
  n.template(
    'ui.cpu.identity',
    'ui.g.cpu',
    'CPU identity',
    1,
    6,
    y,
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

function cpuPanel(top) {
  const row = n.rows(top);
  return [
    n.inject('cpu.poll', 'every second', '1', row(0), ['cpu.state', 'cpu.clock', 'cpu.diag']),
    n.control('cpu.state', 'CPU state', 'state', row(0), ['cpu.lamp', 'cpu.watch', 'cpu.buttons']),
    stateToLamp(row(0)),
    n.stateLamp('ui.cpu.state', 'ui.g.cpu', 'CPU', 2, 3, row(0)),
    n.control('cpu.clock', 'PLC clock', 'clock', row(1.5), ['cpu.clocktext']),
    n.change(
      'cpu.clocktext',
      'date and time',
      [{ t: 'set', p: 'payload', pt: 'msg', to: "$replace($substring(payload, 0, 19), 'T', ' ')", tot: 'jsonata' }],
      X.shape,
      row(1.5),
      ['ui.cpu.clock'],
    ),
    n.text('ui.cpu.clock', 'ui.g.cpu', 'PLC clock', 3, 3, row(1.5)),
    n.control('cpu.diag', 'diagnostics', 'diagnostics', row(3), ['cpu.rows']),
    n.fn('cpu.rows', 'newest ten', NEWEST_TEN, 1, X.shape, row(3), [['ui.cpu.diag']]),
    diagnosticTable(row(3)),
    n.inject('cpu.identify', 'every 10 s', '10', row(4.5), ['cpu.info']),
    n.control('cpu.info', 'CPU identity', 'info', row(4.5), ['ui.cpu.identity']),
    identity(row(4.5)),
    n.cpuButton('ui.cpu.stop', 'Stop CPU', 'stop', 4, '#d32f2f', 'stop', row(6)),
    n.control('cpu.stop', 'stop CPU', 'stop', row(6), ['cpu.lamp', 'cpu.buttons']),
    n.cpuButton('ui.cpu.start', 'Start CPU', 'start', 5, '#1f9d2a', 'play', row(7.5)),
    n.control('cpu.start', 'start CPU', 'start', row(7.5), ['cpu.lamp', 'cpu.buttons']),
    n.fn('cpu.buttons', 'buttons per state', BUTTONS_PER_STATE, 2, X.shape, row(6.75), [['ui.cpu.stop'], ['ui.cpu.start']]),
    ...n.watchdog('cpu', 3, row(9), CPU_WIDGETS),
  ];
}

module.exports = { cpuPanel };
