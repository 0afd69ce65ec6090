/**
 * The connection dialog's fields ⇄ URL in the library (lib/flows/url-fields.ts), without Node-RED: every scheme and
 * parameter the dialog offers, the fingerprint as people type it, the field an invalid URL is blamed on, the
 * parameters no field writes, the CPU presets and what an empty field means. The dialog itself is tested in
 * test/editor-url-browser.test.ts.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { urlAnswer } from '../lib/flows/editor-answers';
import type { UrlFields } from '../lib/flows/url-field-table';
import { urlOfFields } from '../lib/flows/url-fields';
import { fieldsOf, looseFieldsOf, placeholdersOf, presetFields } from '../lib/flows/url-fields-read';
import { DEFAULTS, formatUrl, parseUrl, S7_CPU_PRESETS } from '../lib/url';

const FINGERPRINT = '0123456789ABCDEF'.repeat(4);

/** The URL the fields make, or the test fails with the library's objection. */
function urlOf(fields: UrlFields, kept?: string): string {
  const answer = urlOfFields(fields, kept);
  if (!answer.ok) expect.fail(`${JSON.stringify(fields)}: ${answer.message}`);
  return answer.url;
}

/** The library's objection to the fields, or the test fails. */
function problemOf(fields: UrlFields): { message: string; field?: string; url: string } {
  const answer = urlOfFields(fields);
  if (answer.ok) expect.fail(`${JSON.stringify(fields)} made ${answer.url}`);
  return answer;
}

/** The library's message for a URL it refuses. */
function refusal(url: string): string {
  try {
    parseUrl(url);
  } catch (err) {
    return (err as Error).message;
  }
  return expect.fail(`${url} parses`);
}

describe('flows: the connection dialog fields ⇄ URL', () => {
  describe('every scheme and parameter the dialog offers', () => {
    const cases: [string, UrlFields, string][] = [
      [
        's7, only a host: rack and slot written, every other default left out',
        { protocol: 's7', host: '10.0.0.5' },
        's7://10.0.0.5?rack=0&slot=1',
      ],
      [
        's7, every parameter',
        {
          protocol: 's7',
          host: '10.0.0.5',
          port: '1102',
          addressing: 'rack',
          rack: '0',
          slot: '2',
          connectionType: 'op',
          pduSize: '480',
          timeout: '3000',
          maxItems: '30',
          control: true,
          readOnly: true,
          allow: 'DB1, M ,,',
        },
        's7://10.0.0.5:1102?rack=0&slot=2&type=op&pdu=480&timeout=3000&maxItems=30&control=true&readOnly=true&allow=DB1,M',
      ],
      [
        's7, the defaults typed: left out',
        { protocol: 's7', host: 'plc', port: '102', pduSize: '960', timeout: '5000', connectionType: 'pg' },
        's7://plc?rack=0&slot=1',
      ],
      [
        's7 by TSAPs (rack and slot not written)',
        { protocol: 's7', host: 'logo', addressing: 'tsap', rack: '0', slot: '1', localTsap: '0100', remoteTsap: '0200' },
        's7://logo?localTsap=0100&remoteTsap=0200',
      ],
      ['s7 to an IPv6 address, with or without brackets', { protocol: 's7', host: 'fe80::1', port: '' }, 's7://[fe80::1]?rack=0&slot=1'],
      ['s7 to [::1]', { protocol: 's7', host: '[::1]' }, 's7://[::1]?rack=0&slot=1'],
      [
        's7plus with a pinned certificate, items per request and a timeout',
        {
          protocol: 's7plus',
          host: 'plc',
          port: '4102',
          fingerprint: FINGERPRINT,
          tls: true,
          insecure: false,
          timeout: '2000',
          maxItems: '50',
        },
        `s7plus://plc:4102?fingerprint=${FINGERPRINT}&timeout=2000&maxItems=50`,
      ],
      [
        's7plus trusting a CA file',
        { protocol: 's7plus', host: 'plc', ca: '/etc/plc/ca.pem', tls: true },
        's7plus://plc?ca=%2Fetc%2Fplc%2Fca.pem',
      ],
      [
        's7plus on the bench (any certificate)',
        { protocol: 's7plus', host: 'plc', insecure: true, tls: true },
        's7plus://plc?insecure=true',
      ],
      ['s7plus without TLS (tick taken off)', { protocol: 's7plus', host: 'plc', tls: false }, 's7plus://plc?tls=false'],
      ['s7plus: no tls field sent is TLS on', { protocol: 's7plus', host: 'plc' }, 's7plus://plc'],
      [
        'fetchwrite, one port for both',
        { protocol: 'fetchwrite', host: 'cp', fetchPort: '3000', writePort: '3000', dbUnit: 'byte' },
        'fetchwrite://cp?port=3000&dbUnit=byte',
      ],
      [
        'fetchwrite, two ports',
        { protocol: 'fetchwrite', host: 'cp', fetchPort: '2000', writePort: '2002', timeout: '900' },
        'fetchwrite://cp?fetchPort=2000&writePort=2002&timeout=900',
      ],
      [
        'freeport on a serial port',
        {
          protocol: 'freeport',
          serialPath: '/dev/ttyS1',
          baudRate: '19200',
          parity: 'even',
          dataBits: '7',
          stopBits: '2',
          timeout: '500',
          retries: '5',
          gap: '20',
        },
        'freeport:///dev/ttyS1?baud=19200&parity=even&databits=7&stopbits=2&timeout=500&retries=5&gap=20',
      ],
      [
        'freeport on COM3 (Windows)',
        { protocol: 'freeport', serialPath: 'COM3', baudRate: '9600', parity: 'none', dataBits: '8', stopBits: '1' },
        'freeport://COM3?baud=9600',
      ],
      [
        'freeport through a device server',
        { protocol: 'freeport+tcp', tcpHost: '10.0.0.50', tcpPort: '4001', retries: '0', readOnly: true },
        'freeport+tcp://10.0.0.50:4001?retries=0&readOnly=true',
      ],
    ];
    for (const [what, fields, url] of cases) {
      it(`${what}: ${url}`, () => {
        expect(urlOf(fields)).to.equal(url);
        expect(formatUrl(parseUrl(url)), 'the library writes it so itself').to.equal(url);
      });
    }

    it('a URL read into the fields makes that URL again (every scheme)', () => {
      for (const [, , url] of cases) {
        const read = urlAnswer({ url });
        if (!read.ok || !('fields' in read)) return expect.fail(url);
        expect(urlOf(read.fields), url).to.equal(url);
        expect(fieldsOf(parseUrl(url))).to.deep.equal(read.fields);
      }
    });

    it('fields of the protocols not chosen are not written', () => {
      expect(
        urlOf({ protocol: 'fetchwrite', host: 'cp', fingerprint: FINGERPRINT, rack: '3', serialPath: 'COM1', pduSize: '240' }),
      ).to.equal('fetchwrite://cp?fetchPort=2000&writePort=2001');
    });
  });

  describe('the certificate fingerprint as people type it', () => {
    const colons = FINGERPRINT.match(/../g)!.join(':');
    for (const [how, typed] of [
      ['with colons', colons],
      ['in lower case', FINGERPRINT.toLowerCase()],
      ['with spaces between bytes and around it', ` ${FINGERPRINT.match(/../g)!.join(' ')}\n`],
      ['lower case with colons', colons.toLowerCase()],
    ] as const) {
      it(`${how}: 64 upper-case hex digits in the URL`, () => {
        expect(urlOf({ protocol: 's7plus', host: 'plc', fingerprint: typed, tls: true })).to.equal(
          `s7plus://plc?fingerprint=${FINGERPRINT}`,
        );
      });
    }

    it("a fingerprint one digit short is refused with the library's message, next to the fingerprint field", () => {
      const answer = problemOf({ protocol: 's7plus', host: 'plc', fingerprint: FINGERPRINT.slice(1), tls: true });
      expect(answer.field).to.equal('fingerprint');
      expect(answer.message).to.equal(refusal(answer.url)).and.include('is not a SHA-256 fingerprint');
    });
  });

  describe('fields that make no valid URL: the field to blame, and the URL as composed', () => {
    const cases: [UrlFields, string][] = [
      [{ protocol: 's7', host: '' }, 'host'],
      [{ protocol: 's7', host: 'bad host' }, 'host'],
      [{ protocol: 's7', host: 'plc/x' }, 'host'],
      [{ protocol: 's7', host: 'plc', port: '70000' }, 'port'],
      [{ protocol: 's7', host: 'plc', slot: '40' }, 'slot'],
      [{ protocol: 's7', host: 'plc', pduSize: '12' }, 'pduSize'],
      [{ protocol: 's7', host: 'plc', timeout: '0' }, 'timeout'],
      [{ protocol: 's7', host: 'plc', addressing: 'tsap', localTsap: '1000', remoteTsap: '' }, 'localTsap'],
      [{ protocol: 's7', host: 'plc', addressing: 'tsap', localTsap: '1000', remoteTsap: 'XYZ' }, 'remoteTsap'],
      [{ protocol: 's7plus', host: 'plc', maxItems: '5000', tls: true }, 'maxItems'],
      [{ protocol: 's7plus', host: 'plc', fingerprint: FINGERPRINT, insecure: true, tls: true }, 'fingerprint'],
      [{ protocol: 's7plus', host: 'plc', ca: '/ca.pem', tls: false }, 'ca'],
      [{ protocol: 'fetchwrite', host: 'cp', fetchPort: '0' }, 'fetchPort'],
      [{ protocol: 'freeport', serialPath: '' }, 'serialPath'],
      [{ protocol: 'freeport', serialPath: 'COM1', baudRate: '9601' }, 'baudRate'],
      [{ protocol: 'freeport+tcp', tcpHost: 'gw', tcpPort: '' }, 'tcpPort'],
      [{ protocol: 'freeport+tcp', tcpHost: 'gw', tcpPort: '4001', gap: '-1' }, 'gap'],
    ];
    for (const [fields, field] of cases) {
      it(`${JSON.stringify(fields)}: ${field}`, () => {
        const answer = problemOf(fields);
        expect(answer.field).to.equal(field);
        expect(answer.message).to.match(/^invalid PLC URL/);
        // The composed URL is refused by the parser with this very message: what the dialog saves marks the node invalid.
        if (answer.url !== `${fields.protocol}://`) expect(refusal(answer.url)).to.equal(answer.message);
      });
    }

    it('an unknown protocol is blamed on the protocol field; the answer holds no URL', () => {
      expect(urlOfFields({ protocol: 'modbus', host: 'x' })).to.deep.include({ ok: false, field: 'protocol', url: '' });
    });
  });

  describe('a URL the parser refuses, read into the fields as it stands (the dialog opens on it with the field to fix)', () => {
    const cases: [string, UrlFields, string | undefined][] = [
      [
        's7://plc:1102?rack=0&slot=1&pdu=12&control=true',
        { protocol: 's7', host: 'plc', port: '1102', pduSize: '12', control: true, addressing: 'rack', timeout: '' },
        'pduSize',
      ],
      ['s7://h?localTsap=10', { addressing: 'tsap', localTsap: '10', remoteTsap: '', rack: '' }, 'localTsap'],
      ['fetchwrite://cp?port=0', { fetchPort: '0', writePort: '0' }, 'fetchPort'],
      ['freeport:///dev/ttyS0?baud=9601', { protocol: 'freeport', serialPath: '/dev/ttyS0', baudRate: '9601', parity: '' }, 'baudRate'],
      ['s7plus://plc?TLS=no&fingerprint=AB', { fingerprint: 'AB', tls: false, insecure: false, ca: '' }, 'fingerprint'],
      ['s7://127.0.0.1?rack=0&slott=1', { host: '127.0.0.1', rack: '0', slot: '' }, undefined],
    ];
    for (const [url, fields, field] of cases) {
      it(`${url}: ${field ?? 'no one field (the message under the URL)'}`, () => {
        const answer = urlAnswer({ url });
        expect(answer).to.include({ ok: false, code: 'INVALID_URL' });
        expect((answer as { message: string }).message).to.equal(refusal(url));
        expect((answer as { fields: UrlFields }).fields).to.include(fields);
        expect((answer as { field?: string }).field).to.equal(field);
        expect(looseFieldsOf(url)).to.deep.equal((answer as { fields: UrlFields }).fields);
      });
    }

    it('every field of the protocol is set (none keeps a value from before); no URL or an unknown scheme gives none', () => {
      expect(Object.keys(looseFieldsOf('s7://plc?pdu=1')!)).to.include.members(Object.keys(fieldsOf(parseUrl('s7://plc'))));
      expect(looseFieldsOf('mqtt://x')).to.equal(undefined);
      expect(looseFieldsOf('not a url')).to.equal(undefined);
      expect(urlAnswer({ url: 'mqtt://x' })).not.to.have.property('fields');
    });
  });

  it("keeps the parameters of the URL the fields came from that no field writes (a role, strictSymbols), in that URL's scheme only", () => {
    const kept = 's7plus://plc?type=es&strictSymbols=true&timeout=1';
    expect(urlOf({ protocol: 's7plus', host: 'plc', timeout: '3000', tls: true }, kept)).to.equal(
      's7plus://plc?type=es&timeout=3000&strictSymbols=true',
    );
    expect(urlOf({ protocol: 's7', host: 'plc' }, kept), 'another scheme').to.equal('s7://plc?rack=0&slot=1');
    expect(
      urlOf({ protocol: 'fetchwrite', host: 'cp', fetchPort: '1', writePort: '2' }, 'fetchwrite://cp?port=5'),
      'port= is the port fields',
    ).to.equal('fetchwrite://cp?fetchPort=1&writePort=2');
    expect(urlOf({ protocol: 's7', host: 'plc' }, 'not a URL')).to.equal('s7://plc?rack=0&slot=1');
  });

  it('a CPU preset gives the fields of S7_CPU_PRESETS: rack and slot or the TSAP pair (hex), and items per job', () => {
    for (const [cpu, preset] of Object.entries(S7_CPU_PRESETS)) {
      const fields = presetFields(cpu)!;
      const url = urlOf({ protocol: 's7', host: 'plc', ...fields });
      expect(parseUrl(url), cpu).to.deep.include(preset);
      if (preset.maxItems === undefined) expect(parseUrl(url), cpu).not.to.have.property('maxItems');
    }
    expect(presetFields('s7-200')).to.deep.equal({ addressing: 'tsap', localTsap: '1000', remoteTsap: '1001', maxItems: '' });
    expect(presetFields('toString')).to.equal(undefined);
    expect(urlAnswer({ preset: 'nope' })).to.include({ ok: false, code: 'INVALID_URL' });
  });

  it("says what each empty text field means per protocol: the library's defaults (the freeport timeout is not the S7 one)", () => {
    expect(placeholdersOf('s7')).to.include({
      port: String(DEFAULTS.s7Port),
      rack: '0',
      slot: '1',
      pduSize: '960',
      timeout: '5000',
      maxItems: '20',
    });
    expect(placeholdersOf('s7plus')).to.include({ port: '102', timeout: '5000', maxItems: String(DEFAULTS.s7plusMaxItems) });
    expect(placeholdersOf('fetchwrite')).to.include({ fetchPort: '2000', writePort: '2001', timeout: '5000' });
    expect(placeholdersOf('freeport')).to.include({ timeout: String(DEFAULTS.freeportTimeout), retries: '2', gap: '10' });
    expect(placeholdersOf('freeport+tcp')).to.include({ timeout: '1000' }).and.not.have.any.keys('tcpHost', 'tcpPort');
    expect(placeholdersOf('s7')).not.to.have.any.keys('host');
    expect(placeholdersOf('modbus')).to.deep.equal({});
  });
});

describe("nodes/connection.html holds no scheme's format, default or fingerprint rule (the library's are used)", () => {
  const html = fs.readFileSync(path.join(__dirname, '../../nodes/connection.html'), 'utf8');
  // The one URL it may hold: a new connection node's default value (Node-RED needs it before any runtime answers).
  const NEW_NODE = "url: { value: 's7://192.168.0.1?rack=0&slot=1'";
  const code = html.replace(NEW_NODE, '');

  it('the new node default is there once, and nothing else that writes a URL: no scheme prefix, no query parameter, no encoding', () => {
    expect(html.split(NEW_NODE)).to.have.length(2);
    expect(code).not.to.match(/['"](s7|s7plus|fetchwrite|freeport|freeport\+tcp):\/\/['"]/);
    expect(code).not.to.match(
      /['"][?&]?(rack|slot|pdu|type|timeout|maxItems|fingerprint|ca|insecure|tls|port|fetchPort|writePort|dbUnit|baud|parity|databits|stopbits|retries|gap|readOnly|allow|control|localTsap|remoteTsap)=/,
    );
    expect(code).not.to.match(/encodeURI(Component)?\(/);
  });

  it("no default of the library's URLs as a literal (port 102, PDU 960, timeouts, FETCH/WRITE ports, items per job)", () => {
    for (const value of [
      DEFAULTS.s7Port,
      DEFAULTS.pduSize,
      DEFAULTS.timeout,
      DEFAULTS.fetchPort,
      DEFAULTS.writePort,
      DEFAULTS.freeportTimeout,
    ]) {
      expect(code, String(value)).not.to.match(new RegExp(`(?<![\\w.])${value}(?![\\w.])`));
    }
    expect(code, 'maxItems placeholder').not.to.match(/placeholder="20"/);
  });

  it('no fingerprint rule: no hex pattern, no colon or white space stripping, no case change, no byte split', () => {
    expect(code).not.to.match(/toUpperCase|toLowerCase/);
    expect(code).not.to.match(/\[\\s:\]|\[:\\s\]|\(\.\.\)|0-9A-F|0-9a-f/i);
    expect(code).not.to.match(/hex4|toString\(16\)/);
  });

  it('the rules are found when they are there (the checks above can fail)', () => {
    const old =
      "var p = val('fingerprint').replace(/[\\s:]/g, '').toUpperCase(); base = 's7://' + host + (port !== '102' ? ':' + port : ''); add('pdu', v, '960');";
    expect(old).to.match(/['"](s7|s7plus):\/\/['"]/);
    expect(old).to.match(new RegExp(`(?<![\\w.])${DEFAULTS.s7Port}(?![\\w.])`));
    expect(old).to.match(/toUpperCase/);
    expect(old).to.match(/\[\\s:\]/);
  });
});
