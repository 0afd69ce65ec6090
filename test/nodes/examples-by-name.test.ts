/**
 * The example that reads by name ("S7 tags by name"), run as a user runs it:
 * imported into a real Node-RED, against the simulator built from the source
 * its connection carries (the demo plant, `npx plcwire demo`), its read,
 * write and heartbeat nodes reach the members they name. Only the URL's port
 * changes; the example's nodes and their tags are used as they are.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { shortestFloat32 } from '../../lib/values/float32';
import { ALL_NODES, helper, Recorder, ROOT, until } from './support';

const lib = require(path.join(ROOT, 'dist/lib/index.js'));
const FILE = path.join(ROOT, 'examples/S7 tags by name.json');
const TAB = { id: 'ex.tab', type: 'tab', label: 'S7 tags by name' };

/** The example as Node-RED runs it here: its plcwire nodes on a tab, its debug nodes as recorders, its injects left to the test. */
function runnable(flow: any[], url: string): any[] {
  const nodes = flow.flatMap((n) => {
    if (n.type === 'plcwire-connection') return [{ ...n, url }];
    if (n.type === 'debug') return [{ id: n.id, type: 'helper', z: TAB.id, x: n.x, y: n.y }];
    if (n.type.startsWith('plcwire-')) return [{ ...n, z: TAB.id }];
    return [];
  });
  return [TAB, ...nodes];
}

describe('nodes: the tags-by-name example against the demo plant', function () {
  this.timeout(20000);
  const flow = JSON.parse(fs.readFileSync(FILE, 'utf8')) as any[];
  let plant: any;

  beforeEach(async () => {
    plant = await lib.startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 } });
    await helper.startServer();
  });
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await plant?.close();
  });

  it('its connection carries the source the demo plant is built from, and names every tag its nodes use', () => {
    const conn = flow.find((n) => n.type === 'plcwire-connection');
    expect(conn.symbolSources).to.deep.equal([{ name: lib.PLANT_SOURCE.name, content: lib.PLANT_SOURCE.content }]);
    expect(conn.dbNumbers).to.deep.equal(Object.entries(lib.PLANT_DB_NUMBERS).map(([block, db]) => ({ block, db })));
    const table = lib.compileSymbols(conn.symbolSources, { db: { Plant: 1 } });
    const used = flow.flatMap((n) => [...(n.tags ?? []).map((t: any) => t.address), n.writeAddress, n.watchAddress]).filter(Boolean);
    expect(used.length).to.be.at.least(10);
    for (const name of used) expect(table.lookup(name), name).to.not.equal(undefined);
  });

  it("reads the whole DB by name, writes the run command by name, and the heartbeat sees the PLC's life sign", async () => {
    plant.process.stop();
    for (let i = 0; i < 25; i++) plant.process.step();
    const held = plant.process.snapshot();
    // The read node sends a REAL with the digits TIA shows: the shortest decimal of the same float32.
    const level = shortestFloat32(Math.fround(held.level));
    const temperature = shortestFloat32(Math.fround(held.temperature));
    await helper.load(ALL_NODES, runnable(flow, plant.urls.s7));
    const snapshot = new Recorder(helper.getNode('s7name.debug.demand'));
    const acknowledged = new Recorder(helper.getNode('s7name.debug.write'));
    const polled = new Recorder(helper.getNode('s7name.debug.read'));
    const lifeSign = new Recorder(helper.getNode('s7name.debug.hb'));

    // The poll's first round sends every tag, one message each (nothing was sent before).
    const first: Record<string, unknown> = {};
    while (Object.keys(first).length < 5) {
      const msg = await polled.next(undefined, 8000, 'the first poll');
      first[msg.topic] = msg.payload;
    }
    expect(first).to.deep.equal({ level, temperature, running: false, speed: 0, parts: held.parts });

    helper.getNode('s7name.read.demand').receive({ payload: Date.now() });
    const read = await snapshot.next(undefined, 8000, 'the snapshot');
    expect(read.payload).to.deep.include({
      level,
      run: false,
      running: false,
      heater: held.heater,
      speed: 0,
      parts: held.parts,
      plcHeartbeat: held.heartbeat,
      temperature,
    });
    expect(read.quality).to.deep.equal(Object.fromEntries(Object.keys(read.payload).map((k) => [k, 'good'])));

    const db1: Buffer = plant.memory.area('DB', 1);
    helper.getNode('s7name.write').receive({ payload: { run: true } });
    const ack = await acknowledged.next(undefined, 8000, 'the write acknowledged');
    expect(ack.results).to.deep.equal({ run: { ok: true, address: '"Plant".MotorRun' } });
    expect(db1[4]! & 0x01).to.equal(1);

    // The PLC's program runs again: its life sign counts, ours arrives in "Plant".PcHeartbeat.
    plant.process.start();
    const alive = await lifeSign.next((m) => m.payload?.event === 'alive', 8000, 'alive');
    expect(alive.payload.event).to.equal('alive');
    await until(() => db1.readInt16BE(14) > 0, 8000, '"Plant".PcHeartbeat written');
    await until(() => plant.process.snapshot().speed > 0, 8000, 'the motor turning');
  });
});
