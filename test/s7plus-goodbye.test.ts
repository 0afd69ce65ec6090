/**
 * A clean close over TLS: the client's DeleteObject of its session carries
 * the object id as four fixed bytes before the write IntegrityId
 * (codec/session.ts encodeDeleteObjectRequest). The simulator's session ids
 * start at 0x3A0, whose last byte has bit 7 set: read as a VLQ it would seem
 * to continue into the IntegrityId, and the simulator reset every such
 * goodbye as "counters jumped". Each close here is answered, never refused.
 */
import { expect } from 'chai';
import { S7Server, type S7RefusedEvent } from '../lib/s7/server';
import { S7PlusService } from '../lib/s7plus/server';
import { S7PlusClient } from '../lib/s7plus/client';
import { parseUrl } from '../lib/url';
import type { S7PlusEndpoint } from '../lib/s7plus/url';
import { generateCertificate } from '../lib/s7plus/transport/cert';
import { DB_NUMBERS, SOURCES } from './fixtures/s7plus';
import { until } from './support/wait';

describe('S7CommPlus: a clean close over TLS is a DeleteObject the simulator answers', function () {
  this.timeout(30000);
  let server: S7Server;
  let url: string;
  const refused: S7RefusedEvent[] = [];

  before(async () => {
    const cert = await generateCertificate({ commonName: 'plcwire goodbye test' });
    const service = new S7PlusService({ sources: SOURCES, db: DB_NUMBERS, tls: { cert: cert.cert, key: cert.key } });
    server = new S7Server({ port: 0, profile: 's7-1500', s7plus: service });
    server.on('refused', (e: S7RefusedEvent) => refused.push(e));
    await server.listen();
    url = `s7plus://127.0.0.1:${server.port}?fingerprint=${service.fingerprint!}&timeout=5000`;
  });
  after(() => server.close());

  it('closes sessions 0x3A0 to 0x3A3 (ids whose last byte has bit 7 set) after a write without a single refusal', async () => {
    for (let i = 0; i < 4; i++) {
      const client = new S7PlusClient(parseUrl(url) as S7PlusEndpoint);
      await client.connect();
      expect(await client.read(['"Recipe".Step'])).to.have.property('"Recipe".Step');
      // A write first: the DeleteObject's IntegrityId is then 1 or more, not the 0 that hid the misreading.
      await client.write({ '"Recipe".Step': 3 + i });
      await client.close();
      await until(() => server.connectionCount === 0, 5000, 'the simulator to have no connection');
    }
    expect(refused.map((e) => e.message)).to.deep.equal([]);
  });
});
