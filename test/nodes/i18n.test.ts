/**
 * What users read: the message catalogs and the status texts as Node-RED
 * renders them, in every locale, from the real catalogs (the test helper's
 * `RED._` is the identity, so only these tests see the rendered text).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { freePort } from '../support/net';
import { catalogFiles, LOCALES, loadCatalogs, rawCatalog, withCatalog, type Catalogs, type Locale } from './catalogs';
import { s7Sim } from './sims';
import { helper, nodes, Recorder, ROOT, until, type Sim } from './support';

const status = require(path.join(ROOT, 'nodes/shared/status.js'));

/** Types whose nodes show a status (the config node shows none). */
const SHOWN_BY = ['plcwire-read', 'plcwire-write', 'plcwire-heartbeat', 'plcwire-control', 'plcwire-alarms'];

/** Every key of a catalog, flattened: "plcwire.status.connected". */
function keysOf(catalog: object, prefix = ''): string[] {
  return Object.entries(catalog).flatMap(([k, v]) => (v && typeof v === 'object' ? keysOf(v, `${prefix}${k}.`) : [`${prefix}${k}`]));
}

function valueAt(catalog: any, key: string): unknown {
  return key.split('.').reduce((o, k) => (o == null ? undefined : o[k]), catalog);
}

/** A status text is an i18n key when it has the shape of one; the editor translates those with the node's catalog. */
const isKey = (text: string) => /^plcwire\.[\w.-]+$/.test(text);

interface Shown {
  what: string;
  status: { fill: string; shape: string; text: string };
  numbers: number[];
  /** false: not a row of the README's table (a CPU mode it names in the text). */
  readme?: false;
}

/** Every status the nodes of `type` show, built with `t`, and the numbers each must show. */
function everyStatus(t: (key: string, params?: object) => string, type: string): Shown[] {
  const list: Shown[] = [
    ...['connected', 'connecting', 'closed', 'invalid', 'unconfigured'].map((state) => ({
      what: state,
      status: status.linkStatus(t, { state }),
      numbers: [],
    })),
    { what: 'reconnecting 0.5 s', status: status.linkStatus(t, { state: 'reconnecting', delay: 500 }), numbers: [1] },
    { what: 'reconnecting 30 s', status: status.linkStatus(t, { state: 'reconnecting', delay: 30_000 }), numbers: [30] },
    // Retries that waiting alone will not help say why (issue #31).
    ...[
      { what: 'not trusted', error: { code: 'CERTIFICATE_UNTRUSTED', problem: 'not-trusted' } },
      { what: 'wrong pin', error: { code: 'CERTIFICATE_UNTRUSTED', problem: 'wrong-pin' }, readme: false as const },
      { what: 'certificate expired', error: { code: 'CERTIFICATE_UNTRUSTED', problem: 'expired' } },
      { what: 'certificate not yet valid', error: { code: 'CERTIFICATE_UNTRUSTED', problem: 'not-yet-valid' } },
      { what: 'password refused', error: { code: 'ACCESS_DENIED' } },
    ].map(({ what, error, readme }) => ({
      what,
      status: status.linkStatus(t, { state: 'reconnecting', delay: 30_000, error }),
      numbers: [],
      ...(readme === false ? { readme } : {}),
    })),
    {
      what: 'settings conflict',
      status: status.linkStatus(t, { state: 'invalid', error: { code: 'SETTINGS_CONFLICT' } }),
      numbers: [],
    },
    { what: 'waiting', status: status.waitingStatus(t), numbers: [] },
    { what: 'source error', status: status.linkStatus(t, { state: 'connected', notice: { kind: 'sources' } }), numbers: [] },
    // The widest a layout status gets: the highest DB number and the longest lengths of a standard block.
    ...[
      { db: 1, declared: 20, actual: 24 },
      { db: 65535, declared: 65536, actual: 65534 },
    ].map((n) => ({
      what: `DB${n.db} ${n.declared}≠${n.actual}`,
      status: status.linkStatus(t, { state: 'connected', notice: { kind: 'layout', ...n } }),
      numbers: [n.db, n.declared, n.actual],
    })),
    {
      what: 'DB65535 missing',
      status: status.linkStatus(t, { state: 'connected', notice: { kind: 'layout', db: 65535, declared: 20, actual: null } }),
      numbers: [65535],
    },
  ];
  for (const n of [1, 999]) list.push({ what: `${n} tag errors`, status: status.tagErrorsStatus(t, n), numbers: [n] });
  // A year of one life sign per second.
  for (const n of [1, 31_536_000]) {
    list.push({ what: `sent ${n}`, status: status.sentStatus(t, n), numbers: [n] });
    list.push({ what: `alive ${n}`, status: status.aliveStatus(t, n), numbers: [n] });
  }
  for (const ms of [3_000, 86_400_000]) list.push({ what: `lost ${ms} ms`, status: status.lostStatus(t, ms), numbers: [ms / 1000] });
  if (type === 'plcwire-alarms') {
    // A plant's alarm server holds a few hundred active alarms at most; the widest counts must fit.
    list.push({ what: 'no alarms', status: status.alarmCountsStatus(t, { active: 0, unacknowledged: 0 }), numbers: [] });
    for (const n of [1, 999]) {
      list.push({ what: `${n} active`, status: status.alarmCountsStatus(t, { active: n, unacknowledged: 0 }), numbers: [n] });
      list.push({ what: `${n}/${n} unacked`, status: status.alarmCountsStatus(t, { active: n, unacknowledged: n }), numbers: [n] });
    }
    list.push({ what: 'alarms failed', status: status.alarmsFailedStatus(t), numbers: [] });
    return list;
  }
  if (type !== 'plcwire-control') return list;
  // The README's table has a row for RUN, STOP and STARTUP, and names the rarer modes in the text.
  for (const mode of ['RUN', 'STOP', 'STARTUP']) list.push({ what: `CPU ${mode}`, status: status.cpuStatus(t, mode), numbers: [] });
  for (const mode of ['HOLD', 'DEFECT', 'UNKNOWN', undefined])
    list.push({ what: `CPU ${mode}`, status: status.cpuStatus(t, mode), numbers: [], readme: false });
  // An S7-1500 holds up to 3200 diagnostic entries.
  for (const n of [1, 3200]) {
    list.push({ what: `${n} entries`, status: status.entriesStatus(t, n, false), numbers: [n] });
    list.push({ what: `${n} new entries`, status: status.entriesStatus(t, n, true), numbers: [n] });
  }
  // The README writes the action as ACTION; the longest action name must fit too.
  list.push({ what: 'ACTION failed', status: status.failedStatus(t, 'ACTION'), numbers: [] });
  for (const action of ['diagnostics', 'clock-sync'])
    list.push({ what: `${action} failed`, status: status.failedStatus(t, action), numbers: [], readme: false });
  return list;
}

describe('nodes: message catalogs', () => {
  it('no catalog writes a placeholder as {{name}}: Node-RED interpolates __name__ and shows {{name}} raw', () => {
    const files = catalogFiles().filter((f) => f.endsWith('.json'));
    expect(files.length).to.equal(24);
    for (const file of files) {
      const text = fs.readFileSync(path.join(ROOT, file), 'utf8');
      expect(text.match(/\{\{[^}]*\}\}/g), file).to.equal(null);
    }
  });

  it('every locale has exactly the keys of en-US, with the same placeholders', () => {
    for (const type of Object.keys(JSON.parse(fs.readFileSync(path.join(ROOT, 'package.json'), 'utf8'))['node-red'].nodes)) {
      const en = rawCatalog('en-US', type);
      for (const locale of LOCALES) {
        const other = rawCatalog(locale, type);
        expect(keysOf(other).sort(), `${locale} ${type}`).to.deep.equal(keysOf(en).sort());
        for (const key of keysOf(en)) {
          const placeholders = (s: unknown) => (String(s).match(/__\w+__/g) ?? []).sort();
          expect(placeholders(valueAt(other, key)), `${locale} ${type} ${key}`).to.deep.equal(placeholders(valueAt(en, key)));
        }
      }
    }
  });

  it('every key the nodes and dialogs name exists in the catalog that renders it', () => {
    const dir = path.join(ROOT, 'nodes');
    const sources = [
      ...fs.readdirSync(dir).filter((f) => /\.(js|html)$/.test(f)),
      ...fs.readdirSync(path.join(dir, 'shared')).map((f) => `shared/${f}`),
    ];
    const types = ['plcwire-connection', ...SHOWN_BY];
    let checked = 0;
    for (const file of sources) {
      const text = fs.readFileSync(path.join(dir, file), 'utf8');
      for (const [, key] of text.matchAll(/\b(plcwire(?:-[a-z]+)?(?:\.[A-Za-z][\w-]*){2,})\b/g)) {
        const [prefix] = key!.split('.');
        // The shared "plcwire" section is in every node file's catalog: a shared key can be rendered by any node.
        for (const type of prefix === 'plcwire' ? types : [prefix!]) {
          expect(valueAt(rawCatalog('en-US', type), key!), `${file}: ${key} in ${type}`).to.be.a('string');
          checked++;
        }
      }
    }
    expect(checked).to.be.greaterThan(50);
  });
});

describe('nodes: status texts as Node-RED renders them', function () {
  this.timeout(20000);
  let catalogs: Catalogs;

  before(async () => {
    catalogs = await loadCatalogs();
  });

  for (const locale of LOCALES) {
    it(`${locale}: every status text is translated, shows its number and stays under 20 characters`, () => {
      for (const type of SHOWN_BY) {
        const t = catalogs.translator(locale, type);
        for (const { what, status: s, numbers } of everyStatus(t, type)) {
          const text = isKey(s.text) ? t(s.text) : s.text;
          const label = `${locale} ${type} ${what}: "${text}"`;
          expect(text, label).not.to.match(/\{\{|\}\}|__|^plcwire/);
          for (const n of numbers) expect(text, label).to.include(String(n));
          expect([...text].length, label).to.be.lessThan(20);
        }
      }
    });
  }

  it('the README lists exactly the status texts the nodes show in en-US', () => {
    const readme = fs.readFileSync(path.join(ROOT, 'README.md'), 'utf8');
    const section = readme.slice(readme.indexOf('## Node-RED'), readme.indexOf('\n## ', readme.indexOf('## Node-RED') + 1));
    const documented = new Set([...section.matchAll(/^\| (\w+ (?:dot|ring)) \*([^*]+)\* \|/gm)].map((m) => `${m[1]} ${m[2]}`));
    const shown = new Set<string>();
    for (const type of SHOWN_BY) {
      const t = catalogs.translator('en-US', type);
      for (const { status: s } of everyStatus(t, type).filter((x) => x.readme !== false))
        shown.add(`${s.fill} ${s.shape} ${(isKey(s.text) ? t(s.text) : s.text).replace(/\d+/g, 'N')}`);
    }
    expect([...documented].sort()).to.deep.equal([...shown].sort());
  });
});

describe('nodes: status texts on Status nodes, with the real catalogs', function () {
  this.timeout(20000);
  let sim: Sim;
  let catalogs: Catalogs;

  before(async () => {
    catalogs = await loadCatalogs();
  });

  beforeEach(async () => {
    sim = await s7Sim();
    await helper.startServer();
  });

  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await sim.close();
  });

  /** The catalog text of `key` as a pattern: each placeholder (either syntax) stands for a number. */
  function rendered(locale: Locale, type: string, key: string): RegExp {
    const template = String(valueAt(rawCatalog(locale, type), key));
    const parts = template.split(/__\w+__|\{\{\w+\}\}/).map((p) => p.replace(/[.*+?^${}()|[\]\\]/g, '\\$&'));
    return new RegExp(`^${parts.join('\\d+')}$`);
  }

  for (const locale of LOCALES) {
    it(`${locale}: heartbeat, read, control and a retrying link show their numbers`, async () => {
      const off = await freePort();
      const modules = [
        withCatalog(nodes.connection, catalogs.translator(locale, 'plcwire-connection')),
        withCatalog(nodes.read, catalogs.translator(locale, 'plcwire-read')),
        withCatalog(nodes.heartbeat, catalogs.translator(locale, 'plcwire-heartbeat')),
        withCatalog(nodes.control, catalogs.translator(locale, 'plcwire-control')),
        nodes.status,
      ];
      const at = { z: 'tab', x: 100, y: 100 };
      await helper.load(modules, [
        { id: 'tab', type: 'tab', label: 'i18n' },
        { id: 'conn', type: 'plcwire-connection', url: sim.url },
        { id: 'down', type: 'plcwire-connection', url: `s7://127.0.0.1:${off}?rack=0&slot=1&timeout=500` },
        {
          id: 'alive',
          type: 'plcwire-heartbeat',
          ...at,
          connection: 'conn',
          writeAddress: sim.addr(5),
          writeMode: 'counter',
          interval: 100,
          watchAddress: sim.addr(5),
          timeout: 1000,
          wires: [[]],
        },
        {
          id: 'sent',
          type: 'plcwire-heartbeat',
          ...at,
          connection: 'conn',
          writeAddress: sim.addr(4),
          writeMode: 'counter',
          interval: 100,
          watchAddress: '',
          timeout: 1000,
          wires: [[]],
        },
        {
          id: 'read',
          type: 'plcwire-read',
          ...at,
          connection: 'conn',
          interval: 100,
          output: 'object',
          tags: [
            { name: 'ok', address: sim.addr(0) },
            { name: 'gone', address: sim.missing },
          ],
          wires: [[]],
        },
        {
          id: 'retry',
          type: 'plcwire-read',
          ...at,
          connection: 'down',
          interval: 100,
          output: 'object',
          tags: [{ name: 'a', address: sim.addr(0) }],
          wires: [[]],
        },
        { id: 'ctl', type: 'plcwire-control', ...at, connection: 'conn', action: 'diagnostics', newOnly: false, wires: [[]] },
        { id: 'watcher', type: 'status', ...at, scope: null, wires: [['statuses']] },
        { id: 'statuses', type: 'helper', ...at },
      ]);
      const statuses = new Recorder(helper.getNode('statuses'));
      await until(() => helper.getNode('ctl').linkState === 'connected', 4000, 'control node connected');
      helper.getNode('ctl').receive({});
      const expectations: [string, string, string][] = [
        ['ctl', 'plcwire-control', 'plcwire-control.status.entries'],
        ['alive', 'plcwire-heartbeat', 'plcwire.status.alive'],
        ['sent', 'plcwire-heartbeat', 'plcwire.status.sent'],
        ['read', 'plcwire-read', 'plcwire.status.tagErrors'],
        ['retry', 'plcwire-read', 'plcwire.status.retryIn'],
      ];
      for (const [id, type, key] of expectations) {
        const pattern = rendered(locale, type, key);
        const seen = (m: any) => m.status.source.id === id && typeof m.status.text === 'string' && /\d/.test(m.status.text);
        const msg = await statuses.next(seen, 6000, `a status with a number from "${id}"`);
        expect(msg.status.text, `${id} in ${locale}`).to.match(pattern);
        statuses.skip();
      }
      // Status nodes (and the dashboards built on them) get words, never a catalog key or a placeholder.
      for (const m of statuses.messages) {
        expect(m.status.text, `${m.status.source.id} in ${locale}`).not.to.match(/^plcwire\.|__\w+__|\{\{/);
      }
    });
  }
});
