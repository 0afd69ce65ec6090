/**
 * What a client says about a name its symbol table does not have: the
 * closest names when there are some, and otherwise the members of the
 * longest part of the name that does exist, so `Tank.Nope` is answered as a
 * symbol of "Tank" rather than as a malformed timer address.
 */
import { expect } from 'chai';
import { connect } from '../lib/connect';
import type { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { compileSymbols } from '../lib/symbols/compile';

const TANK = `DATA_BLOCK "Tank"
{ S7_Optimized_Access := 'FALSE' }
VERSION : 0.1
   STRUCT
      Level : Real;
      Motor : Struct
         Run : Bool;
         Speed : Int;
      END_STRUCT;
      Valves : Array[1..3] of Bool;
   END_STRUCT;
BEGIN
END_DATA_BLOCK
`;

describe('unknown names in a client with a symbol table', () => {
  const symbols = compileSymbols([{ name: 'Tank.db', content: TANK }], { db: { Tank: 1 } });
  let server: S7Server;
  let client: S7Client;

  before(async () => {
    server = new S7Server({ port: 0, profile: 's7-300', symbols });
    await server.listen();
    client = (await connect(`s7://127.0.0.1:${server.port}?rack=0&slot=2`, { symbols })) as S7Client;
  });
  after(async () => {
    await client?.close();
    await server.close();
  });

  async function messageOf(name: string): Promise<string> {
    const results = await client.readDetailed([name, '"Tank".Level']);
    expect(results['"Tank".Level']!.ok, 'the known name beside it still reads').to.equal(true);
    const result = results[name]!;
    if (result.ok) throw new Error(`${name} was read`);
    expect(result.error.code).to.equal('INVALID_ADDRESS');
    expect(result.error.tag).to.equal(name);
    return result.error.message;
  }

  it('suggests the closest name for a typo', async () => {
    expect(await messageOf('Tank.Motor.Spede')).to.match(/^unknown symbol Tank\.Motor\.Spede; did you mean "Tank"\.Motor\.Speed\?/);
  });

  it('names the members of the block when nothing in it is close', async () => {
    expect(await messageOf('Tank.Nope')).to.match(
      /^unknown symbol Tank\.Nope; "Tank" has no such member \(its members: Level, Motor, Valves\)/,
    );
  });

  it('names the members of the struct when nothing in it is close', async () => {
    expect(await messageOf('"Tank".Motor.Nope')).to.equal(
      'unknown symbol "Tank".Motor.Nope; "Tank".Motor has no such member (its members: Run, Speed)',
    );
  });

  it("keeps the address parser's words for text that names no block", async () => {
    expect(await messageOf('Nope.x')).to.match(/^invalid address "Nope\.x": not an S7 address/);
  });
});
