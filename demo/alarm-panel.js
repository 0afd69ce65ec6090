'use strict';
/**
 * The demo's alarm panel (issue #33, demo/flows.js): the tank's high level as
 * the plant's two CPU generations raise it (lib/plant/alarms.ts), an ALARM_SQ
 * on the classic S7-300 and a Program_Alarm on the S7-1200, each from an
 * alarms node on its own connection. A function keeps the active alarms (the
 * list asked at start, then every event) and a list widget shows each with its
 * time, text, value, state and acknowledgement, and an Acknowledge button while
 * it waits for one; the button's message goes back to the alarms node of its
 * PLC, which acknowledges it. A refusal (the S7-1200 cannot acknowledge over
 * S7CommPlus yet: docs/alarms.md) comes back through a Catch and is shown
 * under the list, not swallowed.
 */
const n = require('./flow-nodes');

const { X, at } = n;

/** The two PLCs of the panel: the alarms node's id and the name the list shows. */
const PLCS = Object.freeze({ s7classic: { node: 'alm.s7classic', name: 'S7-300' }, s7plus: { node: 'alm.s7plus', name: 'S7-1200' } });

/** The S7-300's connection: the classic CPU of the demo plant (rack 0, slot 2). */
function classicConnection(url) {
  return { id: 'conn.s7classic', type: 'plcwire-connection', name: 'S7-300 sim', url };
}

/**
 * Keeps the active alarms per PLC and makes the list's rows. A classic alarm carries no text (its texts are in
 * the engineering project, as an HMI holds them): the panel has the tank alarm's text, message number 257.
 */
const ALARM_LIST = `const PLCS = ${JSON.stringify(Object.fromEntries(Object.entries(PLCS).map(([k, v]) => [k, v.name])))};
const CLASSIC_TEXTS = { 257: 'Tank level high' };
const list = context.get('list') || {};
let note = context.get('note') || '';
if (msg.error) {
  const from = Object.keys(PLCS).find((k) => msg.error.source && msg.error.source.id === 'alm.' + k) || '';
  const what = msg.ack !== undefined ? 'acknowledging alarm ' + msg.ack + ' refused: ' : '';
  // Node-RED's Catch gives the error as "PlcError: <text>": the text is what the operator reads.
  note = (PLCS[from] || 'alarms') + ': ' + what + String(msg.error.message).replace(/^\\w*Error: /, '');
} else if (msg.topic === 'list' && Array.isArray(msg.payload)) {
  for (const k of Object.keys(list)) if (list[k].plc === msg.plc) delete list[k];
  for (const a of msg.payload) list[msg.plc + ':' + a.id] = { plc: msg.plc, alarm: a };
} else if (msg.payload && msg.payload.type === 'alarm') {
  const a = msg.payload.alarm;
  const k = msg.plc + ':' + a.id;
  if (a.state === 'going' && (a.acknowledged || !a.needsAck)) delete list[k];
  else list[k] = { plc: msg.plc, alarm: a };
  if (msg.payload.change === 'acknowledged') note = '';
} else return null;
context.set('list', list);
context.set('note', note);
const value = (v) => (v === undefined ? '' : typeof v.value === 'number' ? v.value.toFixed(1) : String(v.value));
const rows = Object.keys(list)
  .map((k) => {
    const a = list[k].alarm;
    const en = a.texts && a.texts['en-US'];
    return {
      key: k,
      source: list[k].plc,
      id: a.id,
      plc: PLCS[list[k].plc],
      time: (a.coming || '').slice(0, 19).replace('T', ' '),
      text: en ? en.text : CLASSIC_TEXTS[a.id] || a.kind + ' ' + a.id,
      value: value(a.values && a.values[0]),
      state: a.state,
      ack: !a.needsAck ? 'no acknowledgement needed' : a.acknowledged ? 'acknowledged' : 'unacknowledged',
      canAck: a.needsAck && !a.acknowledged,
    };
  })
  .sort((x, y) => (x.time < y.time ? 1 : x.time > y.time ? -1 : 0));
return { payload: { rows, note } };`;

/** The list: a card per alarm, wrapping on a phone; the button sends { topic: <plc>, ack: <id> } to the router. */
const LIST = `<div class="plcwire-alarms">
  <div v-if="!rows.length" class="plcwire-alarms-none">No active alarms</div>
  <div v-for="a in rows" :key="a.key" class="plcwire-alarm" :data-alarm="a.key" :data-ack="a.ack">
    <div class="plcwire-alarm-head"><b>{{ a.plc }}</b><span>{{ a.time }}</span></div>
    <div class="plcwire-alarm-text">{{ a.text }}</div>
    <div class="plcwire-alarm-meta"><span v-if="a.value">{{ a.value }} %</span><span>{{ a.state }}</span><span>{{ a.ack }}</span></div>
    <v-btn v-if="a.canAck" size="small" color="primary" class="plcwire-alarm-ack" @click="send({ topic: a.source, ack: a.id })">Acknowledge</v-btn>
  </div>
  <div v-if="note" class="plcwire-alarms-note">{{ note }}</div>
</div>
<script>
export default {
  computed: {
    rows() { return (this.msg && this.msg.payload && this.msg.payload.rows) || []; },
    note() { return (this.msg && this.msg.payload && this.msg.payload.note) || ''; },
  },
};
</script>`;

function alarmPanel(top) {
  const row = n.rows(top);
  const alarms = (plc, y) => ({
    id: PLCS[plc].node,
    type: 'plcwire-alarms',
    name: `${PLCS[plc].name} alarms`,
    connection: plc === 's7classic' ? 'conn.s7classic' : 'conn.plus',
    mode: false,
    diagnostics: false,
    // 20 px right of the sources' column: the node with its status text is about 190 px wide, more than the column's 180.
    ...at(X.source + 20, y),
    wires: [[`alm.${plc}.tag`]],
  });
  const tag = (plc, y) =>
    n.change(`alm.${plc}.tag`, PLCS[plc].name, [{ t: 'set', p: 'plc', pt: 'msg', to: plc, tot: 'str' }], X.route, y, ['alm.list']);
  return [
    n.group('ui.g.alarms', 'Alarms', 6, 6),
    // The topic goes in props too: an inject sends only the properties its props name.
    {
      ...n.inject('alm.start', 'active list', '', row(0), ['alm.s7classic', 'alm.s7plus']),
      props: [{ p: 'payload' }, { p: 'topic', vt: 'str' }],
      topic: 'list',
      onceDelay: '3',
    },
    alarms('s7classic', row(1)),
    tag('s7classic', row(1)),
    alarms('s7plus', row(2.5)),
    tag('s7plus', row(2.5)),
    {
      id: 'alm.catch',
      type: 'catch',
      name: 'alarm refusals',
      scope: ['alm.s7classic', 'alm.s7plus'],
      uncaught: false,
      ...at(X.source, row(4)),
      wires: [['alm.list']],
    },
    n.fn('alm.list', 'active alarms', ALARM_LIST, 1, X.shape, row(1.75), [['ui.alarms']]),
    { ...n.template('ui.alarms', 'ui.g.alarms', 'Alarm list', 1, 6, row(1.75), LIST, 0), wires: [['alm.route']] },
    {
      id: 'alm.route',
      type: 'switch',
      name: 'ack to its PLC',
      property: 'topic',
      propertyType: 'msg',
      checkall: 'false',
      outputs: 2,
      rules: [
        { t: 'eq', v: 's7classic', vt: 'str' },
        { t: 'eq', v: 's7plus', vt: 'str' },
      ],
      ...at(X.shape, row(4)),
      wires: [['alm.s7classic'], ['alm.s7plus']],
    },
  ];
}

module.exports = { alarmPanel, classicConnection, PLCS };
