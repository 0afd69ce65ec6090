/**
 * The demo flow (`npm start`) and the example flows, as a person opening
 * them sees them: in the editor no node drawn over another or off the
 * canvas (comments included), on the dashboard every widget inside its
 * group and every group inside the page. The demo's wiring is checked where
 * a mistake would show a value that is not the PLC's: the motor switch
 * shows the polled run bit and never writes it back, and every widget fed
 * by a link is marked stale by that link's watchdog.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import * as vm from 'node:vm';
import { formatAddress, parseAddress } from '../lib/address';
import { parseUrl, S7_CPU_PRESETS } from '../lib/url';
import { DEMO_SYMBOLS, DEMO_TAGS } from '../lib/plant/process';
import { PLANT_DB_NUMBERS, PLANT_SOURCE, TANK_DB_NUMBERS, TANK_SOURCE } from '../lib/plant/source';
import { TANK_DB, TANK_SYMBOLS } from '../lib/plant/tank';
import { buildPlusModel } from '../lib/s7plus/server/model';
import { compileSymbols } from '../lib/symbols';
import { dashboardProblems, drawnBoxes, layoutProblems, placementOf, type FlowNode } from './support/flow-layout';

const ROOT = path.resolve(__dirname, '../..');
const { demoFlow, DEMO_URLS, STALE, LIVE } = require(path.join(ROOT, 'demo/flows.js')) as {
  demoFlow(urls: unknown): FlowNode[];
  DEMO_URLS: unknown;
  STALE: string;
  LIVE: string;
};

function exampleFiles(dir = path.join(ROOT, 'examples')): string[] {
  return fs.readdirSync(dir, { withFileTypes: true }).flatMap((e) => {
    const p = path.join(dir, e.name);
    return e.isDirectory() ? exampleFiles(p) : e.name.endsWith('.json') ? [p] : [];
  });
}

/** The demo flow is deployed as it is (and must stay on the canvas); the examples are imported. */
const flows: [string, FlowNode[], boolean][] = [
  ['the npm start demo flow', demoFlow(DEMO_URLS), true],
  ...exampleFiles().map((f): [string, FlowNode[], boolean] => [path.relative(ROOT, f), JSON.parse(fs.readFileSync(f, 'utf8')), false]),
];

describe('demo flow: tidy in the editor and on the dashboard', () => {
  for (const [name, flow, deployed] of flows) {
    const placement = placementOf(flow, deployed);
    it(`${name} (${deployed ? 'deployed' : 'imported'}, ${placement}): no two nodes overlap on a tab${deployed ? ' and none reaches off the canvas' : ''}`, () => {
      expect(layoutProblems(drawnBoxes(flow, placement), { canvas: deployed })).to.deep.equal([]);
    });
  }

  for (const [name, flow] of flows.filter(([, f]) => f.some((n) => n.type === 'ui-page'))) {
    it(`${name}: every widget fits its group and every group the page`, () => {
      expect(dashboardProblems(flow)).to.deep.equal([]);
    });
  }

  it('finds what it is there to find: nodes on top of each other, a long comment or a status over a node, a widget wider than its group', () => {
    const tab = 't';
    const flow: FlowNode[] = [
      { id: 'read', type: 'plcwire-read', name: 'poll CP', x: 160, y: 100, z: tab, wires: [[]] },
      { id: 'status', type: 'status', name: 'CP link', x: 160, y: 100, z: tab, wires: [[]] },
      { id: 'note', type: 'comment', name: 'A comment long enough to reach the switch to its right', x: 330, y: 200, z: tab },
      { id: 'route', type: 'switch', name: 'by tag', outputs: 5, x: 560, y: 240, z: tab, wires: [[], [], [], [], []] },
      { id: 'edge', type: 'debug', name: 'cut off', x: 40, y: 400, z: tab },
      // A heartbeat's status text ("alive") under it reaches the node one row (40 px) below.
      { id: 'hb', type: 'plcwire-heartbeat', name: 'life sign', x: 160, y: 500, z: tab, wires: [[]] },
      { id: 'below', type: 'status', name: 'link', x: 160, y: 540, z: tab, wires: [[]] },
      // An inject's button, 25 px left of its body, cut off at the canvas edge though the body is not.
      { id: 'clock', type: 'inject', name: 'every second', x: 100, y: 600, z: tab, wires: [[]] },
    ];
    expect(layoutProblems(drawnBoxes(flow, 'centred'), { canvas: true })).to.deep.equal([
      '"poll CP" (read) and "CP link" (status) overlap',
      '"A comment long enough to reach the switch to its right" (note) and "by tag" (route) overlap',
      '"cut off" (edge) reaches off the canvas (left -30, top 385)',
      '"life sign" (hb) and "link" (below) overlap',
      '"every second" (clock) reaches off the canvas (left -5, top 585)',
    ]);
    // Imported without a tab, a node grows to the right of x - 50: a long label runs into its neighbour.
    const row: FlowNode[] = [
      { id: 'inject', type: 'inject', name: 'write {"setpoint": 1500, "motor": true}', x: 250, y: 100, z: tab, wires: [[]] },
      { id: 'write', type: 'plcwire-write', name: 'write setpoint', x: 540, y: 100, z: tab, wires: [[]] },
    ];
    expect(layoutProblems(drawnBoxes(row, 'centred'))).to.deep.equal([]);
    expect(layoutProblems(drawnBoxes(row, 'dropped'))).to.deep.equal([
      '"write {"setpoint": 1500, "motor": true}" (inject) and "write setpoint" (write) overlap',
    ]);
    const dashboard: FlowNode[] = [
      { id: 'page', type: 'ui-page', breakpoints: [{ cols: 3 }, { cols: 12 }] },
      { id: 'g', type: 'ui-group', name: 'narrow', page: 'page', width: 3 },
      { id: 'wide', type: 'ui-group', name: 'too wide', page: 'page', width: 14 },
      { id: 'chart', type: 'ui-chart', name: 'chart', group: 'g', width: 6 },
      { id: 'lost', type: 'ui-text', name: 'lost', group: 'nowhere', width: 1 },
    ];
    expect(dashboardProblems(dashboard)).to.deep.equal([
      'group "too wide" is 14 wide on a page of 12 columns',
      'widget "chart" (chart) is 6 wide in group "narrow" of 3',
      'widget "lost" (lost) is in no group',
    ]);
  });
});

describe('demo flow: the dashboard shows what the PLC holds', () => {
  const flow = demoFlow(DEMO_URLS);
  const node = (id: string) => flow.find((n) => n.id === id)!;
  const feeding = (id: string) =>
    flow.filter((n) => (n.wires as string[][] | undefined)?.some((port) => port.includes(id))).map((n) => n.id);

  it('the motor switch is fed the polled run bit, shows it, and a click writes "Plant".MotorRun without echoing the polled bit back', () => {
    const motor = node('ui.motor');
    expect(motor).to.include({ type: 'ui-switch', passthru: false, decouple: true, topic: DEMO_SYMBOLS.run, topicType: 'str' });
    const route = node('s7.route');
    const run = (route.rules as { v: string }[]).findIndex((r) => r.v === 'run');
    expect((route.wires as string[][])[run]).to.deep.equal(['ui.motor']);
    const tags = node('s7.read').tags as { name: string; address: string }[];
    expect(tags.find((t) => t.name === 'run')?.address).to.equal(DEMO_SYMBOLS.run);
    expect(motor.wires).to.deep.equal([['s7.write']]);
  });

  it('BOOLs from the PLC are lamps, not true/false texts', () => {
    for (const id of ['ui.running', 'ui.heater']) {
      expect(node(id).type, id).to.equal('ui-template');
      expect(String(node(id).format), id).to.match(/class="plcwire-lamp"/);
    }
    const table = compileSymbols([PLANT_SOURCE], { db: PLANT_DB_NUMBERS });
    const tags = node('s7.read').tags as { name: string; address: string }[];
    const bools = tags.filter((t) => table.lookup(t.address)?.dataType === 'BOOL').map((t) => t.name);
    expect(bools).to.have.members(['run', 'running', 'heater']);
  });

  it("the S7 and CP nodes name their tags as the PLC program does, each name one of the plant's addresses; freeport keeps its stations", () => {
    const table = compileSymbols([PLANT_SOURCE], { db: PLANT_DB_NUMBERS });
    const byAddress = new Map(Object.entries(DEMO_TAGS).map(([k, a]) => [formatAddress(parseAddress(a)), k]));
    const named = (connection: string) =>
      flow
        .filter((n) => n.connection === connection)
        .flatMap((n) => [...((n.tags as { address: string }[] | undefined) ?? []).map((t) => t.address), n.writeAddress, n.watchAddress])
        .concat(connection === 'conn.s7' ? [node('ui.motor').topic] : [])
        .filter((a): a is string => typeof a === 'string');
    for (const connection of ['conn.s7', 'conn.fw']) {
      // The connection carries the shipped source, as the editor keeps an uploaded file.
      expect(node(connection).symbolSources).to.deep.equal([{ name: PLANT_SOURCE.name, content: PLANT_SOURCE.content }]);
      expect(node(connection).dbNumbers).to.deep.equal(Object.entries(PLANT_DB_NUMBERS).map(([block, db]) => ({ block, db })));
      const names = named(connection);
      expect(names.length, connection).to.be.at.least(2);
      for (const name of names) {
        expect(name, connection).to.match(/^"Plant"\./);
        const entry = table.lookup(name);
        expect(entry, name).to.not.equal(undefined);
        // The process reads and writes the same bytes (DEMO_TAGS), and the name is the one DEMO_SYMBOLS gives them.
        const tag = byAddress.get(formatAddress(parseAddress(entry!.address!)));
        expect(tag, `${name} is ${entry!.address}, none of DEMO_TAGS`).to.not.equal(undefined);
        expect(DEMO_SYMBOLS[tag as keyof typeof DEMO_SYMBOLS]).to.equal(name);
      }
    }
    expect(node('conn.fp')).to.not.have.property('symbolSources');
    for (const t of node('fp.read').tags as { address: string }[]) expect(t.address).to.match(/^ST\d+,/);
  });

  it("every widget fed by a link is marked stale by that link's watchdog, and only by it", () => {
    const links = { s7: 's7.read', fw: 'fw.read', fp: 'fp.read', plus: 'plus.read' };
    const widgetsOf = (read: string): Set<string> => {
      // Everything downstream of the read node, through routing and shaping nodes.
      const seen = new Set<string>();
      const walk = (id: string) => {
        for (const port of (node(id).wires as string[][] | undefined) ?? []) {
          for (const next of port) {
            if (seen.has(next) || next.endsWith('.watch')) continue;
            seen.add(next);
            walk(next);
          }
        }
      };
      walk(read);
      return new Set([...seen].filter((id) => node(id).type.startsWith('ui-')));
    };
    for (const [prefix, read] of Object.entries(links)) {
      const watch = node(`${prefix}.watch`);
      expect(watch).to.include({ type: 'trigger', op1: 'live', op2: 'stale', extend: true });
      expect(feeding(`${prefix}.watch`)).to.deep.equal([read]);
      const marked = new Set((node(`${prefix}.mark`).wires as string[][])[0]);
      expect([...marked].sort(), prefix).to.deep.equal([...widgetsOf(read)].sort());
      expect(String(node(`${prefix}.mark`).func))
        .to.include(STALE)
        .and.include(LIVE);
    }
  });

  it('the CPU panel: state, clock and diagnostic buffer polled from the S7-1200, and the Stop and Start buttons run those actions on a connection that allows them', () => {
    expect(node('conn.s7').url).to.match(/[?&]control=true(&|$)/);
    const actionOf = (id: string) => node(id).action;
    expect((node('cpu.poll').wires as string[][])[0].map(actionOf).sort()).to.deep.equal(['clock', 'diagnostics', 'state']);
    expect(node('cpu.poll')).to.include({ type: 'inject', repeat: '1', topic: '' });
    for (const [button, action] of [
      ['ui.cpu.stop', 'stop'],
      ['ui.cpu.start', 'start'],
    ]) {
      // The button's topic names the action too, so the node does that and nothing else.
      expect(node(button!)).to.include({ type: 'ui-button', group: 'ui.g.cpu', topic: action, topicType: 'str' });
      const [target] = (node(button!).wires as string[][])[0]!;
      expect(node(target!)).to.include({ type: 'plcwire-control', action, connection: 'conn.s7' });
      // Its answer ({ state }) goes to the lamp and the buttons, never on to another control node (msg.topic would name the action again).
      expect((node(target!).wires as string[][])[0]).to.deep.equal(['cpu.lamp', 'cpu.buttons']);
    }
    for (const n of flow.filter((f) => f.type === 'plcwire-control')) expect(n.connection, n.id).to.equal('conn.s7');
    expect(node('ui.cpu.diag')).to.include({ type: 'ui-table', action: 'replace', autocols: false });
  });

  it('Stop CPU is enabled only in RUN and Start CPU only in STOP, told whenever the state polled or answered by them changes', () => {
    const buttons = node('cpu.buttons');
    expect(buttons.wires).to.deep.equal([['ui.cpu.stop'], ['ui.cpu.start']]);
    expect(feeding('cpu.buttons').sort()).to.deep.equal(['cpu.start', 'cpu.state', 'cpu.stop']);
    // The function's body as Node-RED runs it: msg and a node context.
    const store = new Map<string, unknown>();
    const context = { get: (k: string) => store.get(k), set: (k: string, v: unknown) => store.set(k, v) };
    const fn = vm.runInNewContext(`(function (msg, context) {\n${String(buttons.func)}\n})`) as (msg: unknown, context: unknown) => unknown;
    // Compared as JSON: the objects come from another realm.
    const run = (msg: unknown, ctx: unknown) => JSON.parse(JSON.stringify(fn(msg, ctx))) as unknown;
    expect(run({ payload: { state: 'run' } }, context)).to.deep.equal([{ enabled: true }, { enabled: false }]);
    // Polled again in RUN: nothing new to tell the dashboard.
    expect(run({ payload: { state: 'run' } }, context)).to.equal(null);
    expect(run({ payload: { state: 'stop' } }, context)).to.deep.equal([{ enabled: false }, { enabled: true }]);
    expect(run({ payload: { state: 'startup' } }, context)).to.deep.equal([{ enabled: false }, { enabled: false }]);
    expect(run({ payload: { state: 'run' } }, context)).to.deep.equal([{ enabled: true }, { enabled: false }]);
  });

  it('the S7CommPlus group: the optimized DB read by names the PLC knows, no source file, the setpoint slider writing "Tank".Setpoint without echoing the polled value back', () => {
    expect(node('ui.g.plus').name)
      .to.match(/optimized DB/)
      .and.match(/S7CommPlus/);
    const conn = node('conn.plus');
    expect(conn).to.not.have.property('symbolSources');
    // The simulator's own model: what a browse of the S7-1200 answers.
    const model = buildPlusModel([PLANT_SOURCE, TANK_SOURCE], { db: { ...PLANT_DB_NUMBERS, ...TANK_DB_NUMBERS } });
    const tags = node('plus.read').tags as { name: string; address: string }[];
    const types = tags.map((t) => model.table.lookup(t.address)?.kind);
    expect(types, 'every name is a member of "Tank"').to.deep.equal(['elementary', 'elementary', 'struct', 'array']);
    expect(tags.every((t) => model.table.lookup(t.address)!.db === TANK_DB && model.optimizedDbs.has(TANK_DB))).to.equal(true);
    const slider = node('ui.plus.setpoint');
    expect(slider).to.include({ type: 'ui-slider', passthru: false, topic: TANK_SYMBOLS.setpoint, topicType: 'str' });
    expect(slider.wires).to.deep.equal([['plus.write']]);
    expect(node('plus.write')).to.include({ type: 'plcwire-write', connection: 'conn.plus' });
    const route = node('plus.route');
    const setpoint = (route.rules as { v: string }[]).findIndex((r) => r.v === 'setpoint');
    expect((route.wires as string[][])[setpoint]).to.deep.equal(['ui.plus.setpoint']);
    expect(tags[setpoint]!.address).to.equal(TANK_SYMBOLS.setpoint);
  });

  it('the S7CommPlus URL: pinned by the fingerprint the plant gives, never insecure; without one (the example saved from DEMO_URLS) it pins nothing and trusts nothing', () => {
    const fingerprint = 'AB'.repeat(32);
    const pinned = demoFlow({ ...(DEMO_URLS as object), s7plus: `s7plus://127.0.0.1:10102?fingerprint=${fingerprint}` });
    const endpoint = parseUrl(String(pinned.find((n) => n.id === 'conn.plus')!.url)) as {
      protocol: string;
      fingerprint?: string;
      insecure?: boolean;
      tls?: boolean;
    };
    expect(endpoint).to.include({ protocol: 's7plus', fingerprint });
    expect(endpoint.insecure ?? false).to.equal(false);
    const bare = parseUrl(String(node('conn.plus').url)) as { fingerprint?: string; insecure?: boolean; tls?: boolean };
    expect([bare.fingerprint, bare.insecure ?? false, bare.tls ?? true]).to.deep.equal([undefined, false, true]);
  });

  it("the S7 connection's CPU preset is S7-1200, and its URL addresses the CPU as that preset does (rack and slot)", () => {
    const conn = node('conn.s7');
    expect(conn.cpu).to.equal('s7-1200');
    const preset = S7_CPU_PRESETS[conn.cpu as keyof typeof S7_CPU_PRESETS] as { rack?: number; slot?: number };
    const endpoint = parseUrl(String(conn.url)) as { rack?: number; slot?: number };
    expect({ rack: endpoint.rack, slot: endpoint.slot }).to.deep.equal({ rack: preset.rack, slot: preset.slot });
  });
});
