'use strict';
// The connection doctor against snap7's server, an S7 peer we did not write:
// every step it can pass on a real peer passes, and its DB checks use the
// block info snap7 answers for DBs. For a DB it does not have, snap7's block
// info answer is a malformed frame (the link drops): the doctor reads the
// address once the client is connected again, and the read says 0x0A.
const { expect } = require('chai');
const support = require('./support');
const { startSnap7Server } = support;

describe('interop: the connection doctor against snap7 server', function () {
  this.timeout(20000);
  let snap;

  // One snap7 server for the file (node-snap7 aborts after several servers were created and stopped).
  before(async () => {
    snap = await startSnap7Server({ db: { 1: Buffer.alloc(64), 3: Buffer.alloc(300) }, MK: Buffer.alloc(32) });
  });
  after(() => snap.stop());

  async function doctor(query, addresses) {
    const report = await support.plcwire.diagnose(`s7://127.0.0.1:${snap.port}?${query}&timeout=3000`, addresses);
    // Nothing left open: snap7's own count of its clients.
    const deadline = Date.now() + 2000;
    while (snap.server.ClientsCount() !== 0) {
      if (Date.now() > deadline) throw new Error(`snap7 still has ${snap.server.ClientsCount()} client(s)`);
      await new Promise((r) => setTimeout(r, 10));
    }
    return report;
  }

  it('passes every step and reads the DB lengths by block info', async () => {
    const r = await doctor('slot=2', ['DB1,INT0', 'DB3,INT298']);
    expect(
      r.steps.filter((s) => !s.ok),
      JSON.stringify(r.steps, null, 1),
    ).to.deep.equal([]);
    expect(r.steps.map((s) => s.step)).to.deep.equal([
      'resolve',
      'tcp',
      'cotp',
      'setup',
      'identity',
      'protection',
      'putget',
      'address DB1,INT0',
      'address DB3,INT298',
    ]);
    const by = Object.fromEntries(r.steps.map((s) => [s.step, s]));
    // snap7's server answers with the canned lists of a CPU 315-2 PN/DP.
    expect(by.identity.detail).to.contain('family S7-300');
    expect(by['address DB3,INT298'].detail).to.equal('DB3 exists, 300 bytes (block info); DB3,INT298 = 0');
  });

  it('finds a DB that does not exist and one too short for the address', async () => {
    let r = await doctor('slot=2', ['DB9,INT0']);
    expect(r.steps[r.steps.length - 1]).to.include({ step: 'address DB9,INT0', ok: false });
    expect(r.steps[r.steps.length - 1].detail).to.match(/^DB9 does not exist/);
    r = await doctor('slot=2', ['DB1,DINT62']);
    expect(r.steps[r.steps.length - 1]).to.include({ ok: false, detail: 'DB1 has 64 bytes (block info); DB1,DINT62 needs bytes 62..65' });
  });
});
