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
 *
 * The S7-1200's optimized DB "Tank" has no offsets and no source on the
 * connection: its own s7plus:// connection (TLS, pinned by the fingerprint
 * of the certificate the plant made at start) reads it by the names the PLC
 * answers a browse with, and its setpoint slider writes by name (plus-panel.js).
 *
 * The flow is put together from small parts: node builders in flow-nodes.js,
 * the panels in panels.js, cpu-panel.js and plus-panel.js, the dashboard's CSS in dashboard.css.
 */
const fs = require('node:fs');
const path = require('node:path');
const { PITCH, STALE, LIVE } = require('./flow-nodes');
const { intro, dashboard, connections, s7Panel, linkPanel, errorsAndStyle } = require('./panels');
const { cpuPanel } = require('./cpu-panel');
const { plusConnection, plusPanel } = require('./plus-panel');
const { alarmPanel, classicConnection } = require('./alarm-panel');

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

/** The first row of each panel, top to bottom: S7, its CPU, CP, S7-200, S7CommPlus, errors and CSS. */
const TOPS = Object.freeze({
  s7: 140,
  cpu: 140 + 13 * PITCH,
  fw: 140 + 24 * PITCH,
  fp: 140 + 29 * PITCH,
  plus: 140 + 34 * PITCH,
  errors: 140 + 41 * PITCH,
  alarms: 140 + 43 * PITCH,
});

/** @param {{ s7: string, s7plus: string, fetchwrite: string, freeport: string, s7classic: string }} urls */
function demoFlow(urls) {
  const symbols = () => ({ symbolSources: [{ ...PLANT_SOURCE }], dbNumbers: PLANT_DB_NUMBERS.map((d) => ({ ...d })) });
  return [
    ...intro(),
    ...dashboard(),
    ...connections(urls, symbols),
    plusConnection(urls.s7plus),
    ...s7Panel(TOPS.s7),
    ...cpuPanel(TOPS.cpu),
    // FETCH/WRITE: the same DB1 through the CP, by the same names (the CP serves the CPU's data blocks).
    ...linkPanel(
      'fw',
      {
        poll: 'poll CP',
        link: 'CP link',
        tags: [
          { name: 'level', address: '"Plant".Level' },
          { name: 'parts', address: '"Plant".Parts' },
        ],
      },
      TOPS.fw,
    ),
    // Freeport: stations 5 (level, REAL) and 6 (parts, DINT) on the RS-485 bus, through a serial device server.
    ...linkPanel(
      'fp',
      {
        poll: 'poll S7-200',
        link: 'S7-200 link',
        tags: [
          { name: 'level', address: 'ST5,REAL0' },
          { name: 'parts', address: 'ST6,DINT0' },
        ],
      },
      TOPS.fp,
    ),
    // S7CommPlus: the S7-1200's optimized DB "Tank" by name, browsed from the PLC (no source file), over TLS.
    ...plusPanel(TOPS.plus),
    ...errorsAndStyle(TOPS.errors),
    // Alarms (issue #33): the tank's high level from the S7-300 and the S7-1200, acknowledged from the list.
    classicConnection(urls.s7classic),
    ...alarmPanel(TOPS.alarms),
  ];
}

/**
 * The demo plant's default URLs (`npx plcwire demo`). The s7plus one carries no fingerprint: the simulator's
 * certificate is each user's own (made on the first start, then kept: demoCertificateDir()), so a flow saved from
 * these URLs (the Dashboard 2 example) pins it once with Get certificate;
 * `npm start` gives the running plant's URLs, pinned.
 */
const DEMO_URLS = Object.freeze({
  s7: 's7://127.0.0.1:10102?rack=0&slot=1',
  s7plus: 's7plus://127.0.0.1:10102',
  fetchwrite: 'fetchwrite://127.0.0.1?fetchPort=12000&writePort=12001',
  freeport: 'freeport+tcp://127.0.0.1:14001',
  s7classic: 's7://127.0.0.1:10103?rack=0&slot=2',
});

module.exports = { demoFlow, DEMO_URLS, PLANT_SOURCE, PLANT_DB_NUMBERS, STALE, LIVE };

// `node demo/flows.js` regenerates the Dashboard 2 example from this flow.
if (require.main === module) {
  const dir = path.join(__dirname, '..', 'examples', 'Dashboard 2');
  fs.mkdirSync(dir, { recursive: true });
  fs.writeFileSync(path.join(dir, 'Plant dashboard for all three protocols.json'), `${JSON.stringify(demoFlow(DEMO_URLS), null, 2)}\n`);
}
