'use strict';
// snap7's client against our S7Server built from a DB source: a foreign
// client sees the bytes a CPU holds after the download of that source.
const { expect } = require('chai');
const fs = require('node:fs');
const path = require('node:path');
const support = require('./support');
const { snap7Client } = support;

const FIXTURE = path.resolve(__dirname, '../fixtures/symbols/cli/Tank.db');
// The same bytes test/symbols-simulator.test.ts computes by hand, member by member.
const TANK_HEX = [
  '41480000',
  '05',
  '00',
  'fffe',
  '0602414200000000',
  '0300000000',
  '00',
  '00030002004800e90000',
  '07e80501040c1e0f00000000',
  '07b201010500000000000000',
  '000300040005',
  '05',
  '02',
  '3fc00000',
  '01',
  '00',
].join('');

describe('interop: snap7 client against our S7Server built from DB sources', function () {
  let server;
  let peer;

  before(async () => {
    const dist = (file) => require(path.resolve(__dirname, '../../dist/lib/symbols', file));
    const blocks = dist('source-parser.js').parseBlockSource({ name: 'Tank.db', content: fs.readFileSync(FIXTURE) });
    const symbols = dist('compile.js').compileDeclarations(blocks, [], { db: { Tank: 1 } }, dist('literals.js').literalValue);
    server = new support.plcwire.S7Server({ port: 0, profile: 's7-300', symbols });
    peer = await snap7Client(await server.listen(), { rack: 0, slot: 2 });
  });

  after(async () => {
    if (peer) peer.close();
    if (server) await server.close();
  });

  it('DBRead of the whole block gives the start values, string headers and DTL initial values', async () => {
    const data = await peer.call('DBRead', 1, 0, 70);
    expect(data.toString('hex')).to.equal(TANK_HEX);
  });

  it('DBGet reads exactly the declared length, as GetAgBlockInfo reports it', async () => {
    expect((await peer.call('DBGet', 1)).toString('hex')).to.equal(TANK_HEX);
    expect(await peer.call('GetAgBlockInfo', 0x41, 1)).to.deep.include({ BlkNumber: 1, MC7Size: 70 });
    expect(await peer.call('ListBlocksOfType', 0x41)).to.deep.equal([1]);
  });
});
