/**
 * The example "S7CommPlus optimized DB by name", as its comment tells a user
 * to run it: imported as it is, its connection trusts no certificate, so the
 * link is refused before any S7CommPlus data, with an error on Catch that
 * shows the certificate's fingerprint and the `fingerprint=` that pins it;
 * pinned (what *Get certificate* and *Pin this certificate* put in the URL),
 * its nodes read the demo plant's optimized DB "Tank" by name, with no source
 * file, and write its setpoint. Only the URL's port changes.
 */
import { shortestFloat32 } from '../../lib/values/float32';
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { ALL_NODES, helper, Recorder, ROOT, until } from './support';

const lib = require(path.join(ROOT, 'dist/lib/index.js'));
const FILE = path.join(ROOT, 'examples/S7CommPlus optimized DB by name.json');
const TAB = { id: 'ex.tab', type: 'tab', label: 'S7CommPlus optimized DB by name' };

/** The example on a tab, its connection at `url`, its debug nodes as recorders, a Catch node for the tab. */
function runnable(flow: any[], url: string): any[] {
  const nodes = flow.flatMap((n) => {
    if (n.type === 'plcwire-connection') return [{ ...n, url }];
    if (n.type === 'debug') return [{ id: n.id, type: 'helper', z: TAB.id, x: n.x, y: n.y }];
    if (n.type.startsWith('plcwire-')) return [{ ...n, z: TAB.id }];
    return [];
  });
  return [
    TAB,
    ...nodes,
    { id: 'ex.catch', type: 'catch', z: TAB.id, scope: null, uncaught: false, wires: [['ex.caught']] },
    { id: 'ex.caught', type: 'helper', z: TAB.id },
  ];
}

describe('nodes: the S7CommPlus example against the demo plant', function () {
  this.timeout(30000);
  const flow = JSON.parse(fs.readFileSync(FILE, 'utf8')) as any[];
  const conn = flow.find((n) => n.type === 'plcwire-connection');
  let plant: any;
  /** The example's URL at the plant's port. */
  let bare: string;

  beforeEach(async () => {
    plant = await lib.startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 } });
    bare = conn.url.replace(':10102', `:${plant.ports.s7}`);
    await helper.startServer();
  });
  afterEach(async () => {
    await helper.unload();
    await helper.stopServer();
    await plant?.close();
  });

  it('its connection is S7CommPlus with TLS, trusts nothing by itself (no pin, no CA, never insecure) and holds no source file', () => {
    expect(conn.url).to.equal('s7plus://127.0.0.1:10102');
    expect(conn).to.not.have.property('symbolSources');
    const used = flow.flatMap((n) => (n.tags ?? []).map((t: any) => t.address));
    expect(used.length).to.be.at.least(5);
    for (const name of used) expect(name, name).to.match(/^"Tank"\./);
  });

  it("as imported: the link is refused, the error on Catch shows the PLC's fingerprint and the parameter that pins it", async () => {
    await helper.load(ALL_NODES, runnable(flow, bare));
    const caught = new Recorder(helper.getNode('ex.caught'));
    const polled = new Recorder(helper.getNode('s7plus.debug.read'));
    const msg = await caught.next((m) => m.error?.code === 'CERTIFICATE_UNTRUSTED', 15000, 'the untrusted certificate on Catch');
    expect(msg.error.message).to.include(`fingerprint=${plant.s7plus.fingerprint}`);
    // Nothing was read: no poll delivered a value of the PLC.
    expect(polled.messages.filter((m) => m.payload && Object.values(m.payload).some((v) => v !== null))).to.deep.equal([]);
  });

  it('pinned as Get certificate and Pin do: reads "Tank" whole and by member with the values the plant holds, and writes the setpoint by name', async () => {
    const pinned = `${bare}?fingerprint=${plant.s7plus.fingerprint}`;
    plant.process.stop();
    for (let i = 0; i < 25; i++) plant.process.step();
    const tank = plant.tank.snapshot();
    await helper.load(ALL_NODES, runnable(flow, pinned));
    const polled = new Recorder(helper.getNode('s7plus.debug.read'));
    const first = await polled.next((m) => m.payload?.setpoint !== undefined, 15000, 'the first poll');
    // REALs with the digits TIA shows (lib/symbols/reals.ts through the browsed table), as over s7:// with sources.
    const { levels, ...rest } = first.payload;
    expect(rest).to.deep.equal({ phase: tank.phase, setpoint: 42.5, drive: { Running: false, Speed: 0, Current: 0 } });
    expect(levels).to.deep.equal(tank.levels.map((v: number) => shortestFloat32(v)));
    expect(
      levels.some((v: number) => v !== Math.fround(v)),
      'a level shown as its float32 would have more digits',
    ).to.equal(true);
    const drive = new Recorder(helper.getNode('s7plus.debug.drive'));
    helper.getNode('s7plus.read.drive').receive({ payload: Date.now() });
    const read = await drive.next(undefined, 8000, 'the drive read');
    expect(read.payload).to.deep.include({ drive: { Running: false, Speed: 0, Current: 0 }, speed: 0 });
    expect(read.payload['newest level']).to.equal(shortestFloat32(tank.levels[0]));
    const acknowledged = new Recorder(helper.getNode('s7plus.debug.write'));
    helper.getNode('s7plus.write').receive({ payload: { '"Tank".Setpoint': 45 } });
    const ack = await acknowledged.next(undefined, 8000, 'the write acknowledged');
    expect(
      Object.values(ack.results).every((r: any) => r.ok),
      JSON.stringify(ack.results),
    ).to.equal(true);
    await until(() => plant.tank.snapshot().setpoint === 45, 8000, '"Tank".Setpoint written in the PLC');
  });
});
