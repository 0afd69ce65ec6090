/**
 * s7plus:// URLs (lib/s7plus/url.ts) through the registry, and the password:
 * refused in a URL without being echoed, kept out of every property, JSON,
 * inspect() output and error of the client.
 */
import { expect } from 'chai';
import * as util from 'node:util';
import { createClient } from '../lib/connect';
import { PlcError } from '../lib/errors';
import { S7PlusClient } from '../lib/s7plus/client';
import { normalizeFingerprint } from '../lib/s7plus/transport/fingerprint';
import { parseFingerprint } from '../lib/s7plus/transport/trust';
import { DEFAULTS, endpointKey, endpointName, formatUrl, parseUrl } from '../lib/url';

const PIN = 'fe06cd29ad6cfb8ba333f3b410ebc5c33cb62493f317c44e104e8f4b09bf827a';
const PIN_COLONS = PIN.toUpperCase().replace(/(..)(?!$)/g, '$1:');

function refused(text: string): PlcError {
  try {
    parseUrl(text);
  } catch (err) {
    expect(err).to.be.instanceOf(PlcError);
    expect((err as PlcError).code).to.equal('INVALID_URL');
    return err as PlcError;
  }
  throw new Error(`${text} was accepted`);
}

describe('s7plus client: URLs', () => {
  it('reads s7plus://host with the defaults: port 102, TLS on, role hmi, timeout 5000', () => {
    expect(parseUrl('s7plus://192.168.0.10')).to.deep.equal({
      protocol: 's7plus',
      host: '192.168.0.10',
      port: 102,
      tls: true,
      role: 'hmi',
      timeout: 5000,
    });
    expect(DEFAULTS).to.include({ s7plusPort: 102, s7plusMaxItems: 20 });
  });

  it('takes a fingerprint with colons, spaces or either case, and keeps 64 upper-case hex digits (the form fingerprint256 gives)', () => {
    const upper = PIN.toUpperCase();
    expect(parseUrl(`s7plus://plc?fingerprint=${PIN_COLONS}`)).to.include({ fingerprint: upper });
    expect(parseUrl(`s7plus://plc?fingerprint=${PIN}`)).to.include({ fingerprint: upper });
    expect(formatUrl(parseUrl(`s7plus://plc?fingerprint=${PIN}`))).to.equal(`s7plus://plc?fingerprint=${upper}`);
    expect(normalizeFingerprint(PIN_COLONS.replace(/:/g, ' '))).to.equal(upper);
    // The trust decision reads it by the same rule.
    expect(parseFingerprint(PIN_COLONS.toLowerCase())).to.equal(upper);
    expect(normalizeFingerprint(PIN.slice(2))).to.equal(undefined);
    const err = refused(`s7plus://plc?fingerprint=${PIN.slice(1)}`);
    expect(err.message).to.contain('not a SHA-256 fingerprint (64 hex digits');
  });

  it('reads ca=, insecure=true, tls=false, type, timeout and maxItems, and formats them back', () => {
    const text = 's7plus://10.0.0.2:1102?ca=%2Fetc%2Fplc%2Fca.pem&type=es&timeout=900&maxItems=7&readOnly=true';
    const e = parseUrl(text);
    expect(e).to.deep.include({
      protocol: 's7plus',
      port: 1102,
      ca: '/etc/plc/ca.pem',
      role: 'es',
      timeout: 900,
      maxItems: 7,
      readOnly: true,
    });
    expect(parseUrl(formatUrl(e))).to.deep.equal(e);
    expect(parseUrl('s7plus://plc?insecure=true')).to.include({ insecure: true, tls: true });
    const plain = parseUrl('s7plus://plc?tls=false');
    expect(plain).to.include({ tls: false });
    expect(formatUrl(plain)).to.equal('s7plus://plc?tls=false');
    expect(formatUrl(parseUrl(`s7plus://plc?fingerprint=${PIN_COLONS}`))).to.equal(`s7plus://plc?fingerprint=${PIN.toUpperCase()}`);
    expect(endpointName(parseUrl('s7plus://[::1]:1102'))).to.equal('s7plus://[::1]:1102');
    expect(endpointKey(parseUrl('s7plus://PLC'))).to.equal(endpointKey(parseUrl(`s7plus://plc?fingerprint=${PIN}`)));
    expect(endpointKey(parseUrl('s7plus://plc'))).to.not.equal(endpointKey(parseUrl('s7plus://plc?type=es')));
  });

  it('refuses trust parameters that contradict each other, and tls=false with any of them', () => {
    expect(refused(`s7plus://plc?tls=false&fingerprint=${PIN}`).message).to.contain('tls=false has no certificate to check');
    expect(refused('s7plus://plc?tls=false&insecure=true').message).to.contain('drop insecure=');
    expect(refused(`s7plus://plc?insecure=true&fingerprint=${PIN}`).message).to.contain('insecure=true accepts any certificate');
    expect(refused('s7plus://plc?ca=').message).to.contain('ca= names no file');
    expect(refused('s7plus://plc?maxItems=0').message).to.contain('maxItems=0 is out of range');
    expect(refused('s7plus://plc?rack=0').message).to.contain('unknown parameter "rack"');
  });

  it('refuses password= with the ways to give it, and never echoes it, however it is spelt', () => {
    for (const text of [
      's7plus://10.0.0.2?password=Sup3rSecret',
      's7plus://10.0.0.2?PassWord=Sup3rSecret&timeout=900',
      's7plus://10.0.0.2?pass%77ord=Sup3rSecret',
      's7plus://10.0.0.2?password=Sup%33rSecret',
    ]) {
      const err = refused(text);
      expect(err.message, text).to.contain('a PLC password never goes into a URL');
      expect(err.message, text).to.contain('connect(url, { password })');
      expect(err.message, text).to.contain('PLCWIRE_PASSWORD');
      expect(err.message, text).to.contain('--password-file');
      expect(err.message, text).to.not.match(/Sup3rSecret|Sup%33rSecret/);
      expect(JSON.stringify(err), text).to.not.contain('Secret');
    }
  });
});

describe('s7plus client: the registry and the password', () => {
  it('an s7plus:// URL makes an S7PlusClient', async () => {
    const client = createClient('s7plus://127.0.0.1:1?tls=false');
    expect(client).to.be.instanceOf(S7PlusClient);
    expect(client.protocol).to.equal('s7plus');
    expect(client.tag('DB1.DBW2').byteOffset).to.equal(2);
    await client.close();
  });

  it('keeps the password out of the client: no property, JSON, inspect() or connect error shows it', async () => {
    const client = createClient('s7plus://127.0.0.1:1?tls=false&timeout=500', { password: 'Sup3rSecret' });
    expect(JSON.stringify(client)).to.not.contain('Sup3rSecret');
    expect(util.inspect(client, { depth: 5, showHidden: true })).to.not.contain('Sup3rSecret');
    let err: unknown;
    try {
      await client.connect();
    } catch (e) {
      err = e;
    }
    expect(err).to.be.instanceOf(PlcError);
    // Nothing listens on port 1: the connection fails before the password step (test/s7plus-legitimation.test.ts gives it).
    expect((err as PlcError).code).to.equal('CONNECT_FAILED');
    expect(util.inspect(err, { depth: 5 })).to.not.contain('Sup3rSecret');
    await client.close();
  });
});
