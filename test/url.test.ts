import { expect } from 'chai';
import { connect } from '../lib/connect';
import { PlcError } from '../lib/errors';
import { DEFAULTS, endpointKey, formatUrl, isLoopback, parseUrl, S7_CPU_PRESETS } from '../lib/url';

function urlError(text: string): PlcError {
  try {
    parseUrl(text);
  } catch (err) {
    expect(err).to.be.instanceOf(PlcError);
    expect((err as PlcError).code).to.equal('INVALID_URL');
    return err as PlcError;
  }
  throw new Error(`${text} was accepted`);
}

describe('url: parseUrl', () => {
  it('reads an S7 URL with defaults (port 102, rack 0, slot 1, PG, PDU 960)', () => {
    expect(parseUrl('s7://192.168.0.2?rack=0&slot=1')).to.deep.equal({
      protocol: 's7',
      host: '192.168.0.2',
      port: 102,
      rack: 0,
      slot: 1,
      connectionType: 'pg',
      pduSize: 960,
      timeout: 5000,
    });
  });

  it('refuses credentials in a URL without repeating them in the error', () => {
    let err: unknown;
    try {
      parseUrl('s7://admin:s3cret@10.0.0.2?rack=0&slot=1');
    } catch (e) {
      err = e;
    }
    expect(err).to.be.instanceOf(PlcError);
    expect((err as PlcError).code).to.equal('INVALID_URL');
    expect((err as PlcError).message).to.match(/no user name or password/);
    expect((err as PlcError).message).not.to.include('s3cret');
  });

  it('never repeats a password given as a URL parameter, whatever else is wrong with the URL', () => {
    for (const url of [
      's7://10.0.0.2?rack=0&slot=1&password=hunter2',
      's7://10.0.0.2?Password=hunter2&bogus=1',
      'fetchwrite://10.0.0.2?pwd=hunter2&fetchPort=x',
      's7plus://10.0.0.2?password=hunter2&bogus=1',
    ]) {
      let err: unknown;
      try {
        parseUrl(url);
      } catch (e) {
        err = e;
      }
      expect(err, url).to.be.instanceOf(PlcError);
      expect((err as PlcError).code, url).to.equal('INVALID_URL');
      expect((err as PlcError).message, url).not.to.include('hunter2');
    }
  });

  it('reads TSAPs in hex, the connection type, PDU, timeout and an IPv6 host', () => {
    const e = parseUrl('s7://[::1]:1102?localTsap=1000&remoteTsap=4D57&type=OP&pdu=240&timeout=250');
    expect(e).to.include({
      host: '::1',
      port: 1102,
      localTsap: 0x1000,
      remoteTsap: 0x4d57,
      connectionType: 'op',
      pduSize: 240,
      timeout: 250,
    });
  });

  it('reads the item limit per S7 job (maxItems, 1–255); without it the client uses 20', () => {
    expect(parseUrl('s7://h?maxItems=60')).to.include({ maxItems: 60 });
    expect(parseUrl('s7://h?maxitems=1')).to.include({ maxItems: 1 });
    expect(parseUrl('s7://h?maxItems=255')).to.include({ maxItems: 255 });
    expect(parseUrl('s7://h')).to.not.have.property('maxItems');
    expect(DEFAULTS.maxItems).to.equal(20);
    for (const bad of ['0', '256', '20.5', '-1', 'many']) {
      const err = urlError(`s7://h?maxItems=${bad}`);
      expect(err.message, bad).to.include(`maxItems=${bad}`);
    }
    expect(urlError('s7://h?maxItems=256').message).to.include('out of range (1–255)');
    expect(urlError('fetchwrite://h?maxItems=20').message).to.include('unknown parameter "maxItems"');
  });

  it('CPU presets allow more than 20 items per job only where the CPU serves them (S7-1200, S7-1500, S7-400)', () => {
    const limits = Object.fromEntries(Object.entries(S7_CPU_PRESETS).map(([cpu, p]) => [cpu, p.maxItems ?? DEFAULTS.maxItems]));
    expect(limits).to.deep.equal({ 's7-1500': 255, 's7-1200': 255, 's7-400': 255, 's7-300': 20, logo: 20, 's7-200': 20 });
  });

  it('reads FETCH/WRITE with two ports, one port, and the DB unit', () => {
    expect(parseUrl('fetchwrite://10.0.0.5')).to.include({ fetchPort: 2000, writePort: 2001, dbUnit: 'word' });
    expect(parseUrl('fetchwrite://10.0.0.5?fetchPort=3000&writePort=3001&dbUnit=byte')).to.include({
      fetchPort: 3000,
      writePort: 3001,
      dbUnit: 'byte',
    });
    expect(parseUrl('fetchwrite://10.0.0.5?port=2000')).to.include({ fetchPort: 2000, writePort: 2000 });
  });

  it('reads freeport over a serial port (Unix and Windows names) and over TCP', () => {
    const serial = parseUrl('freeport:///dev/ttyUSB0?baud=19200&parity=even&databits=7&stopbits=1&retries=0&gap=5');
    expect(serial).to.deep.include({
      transport: { kind: 'serial', path: '/dev/ttyUSB0', baudRate: 19200, parity: 'even', dataBits: 7, stopBits: 1 },
      retries: 0,
      interFrameGapMs: 5,
      timeout: 1000,
    });
    expect(parseUrl('freeport://COM3?baud=9600')).to.deep.include({
      transport: { kind: 'serial', path: 'COM3', baudRate: 9600, parity: 'none', dataBits: 8, stopBits: 1 },
    });
    expect(parseUrl('freeport+tcp://gw.local:4001?timeout=500')).to.deep.include({
      transport: { kind: 'tcp', host: 'gw.local', port: 4001 },
      timeout: 500,
    });
  });

  it('reads the safety options on every protocol', () => {
    expect(parseUrl('s7://h?readOnly=true')).to.include({ readOnly: true });
    expect(parseUrl('s7://h?control=true')).to.include({ control: true });
    expect(parseUrl('s7://h?control=false')).to.not.have.property('control');
    expect(parseUrl('s7://h')).to.not.have.property('control');
    expect(parseUrl('fetchwrite://h?allow=DB10,M&allow=DB1.DBW2')).to.deep.include({ allow: ['DB10', 'M', 'DB1.DBW2'] });
  });

  it('refuses what is wrong, naming the part', () => {
    expect(urlError('').message).to.include('empty');
    expect(urlError('modbus://h').message).to.include('unknown protocol "modbus:"');
    expect(urlError('s7://h?slott=1').message).to.include('unknown parameter "slott"');
    expect(urlError('s7://h?rack=9').message).to.include('rack=9 is out of range (0–7)');
    expect(urlError('s7://h?slot=x').message).to.include('slot=x is not a whole number');
    expect(urlError('s7://h?localTsap=1000').message).to.include('go together');
    expect(urlError('s7://h?localTsap=zz&remoteTsap=1').message).to.include('not a hex TSAP');
    expect(urlError('s7://?rack=0').message).to.include('no host');
    expect(urlError('s7://h?control=maybe').message).to.include('control=maybe must be true or false');
    expect(urlError('fetchwrite://h?control=true').message).to.include('unknown parameter "control"');
    expect(urlError('freeport:///dev/ttyS0?baud=14400').message).to.include('baud=14400 is not a rate');
    expect(urlError('freeport:///dev/ttyS0?parity=mark').message).to.include('parity=mark must be one of none, even, odd');
    expect(urlError('freeport+tcp://gw').message).to.include('needs a port');
    expect(urlError('fetchwrite://h:2000').message).to.include('fetchPort');
    expect(urlError('fetchwrite://h?port=1&fetchPort=2').message).to.include('either port');
  });

  it('a port above 65535 or not a number is named as the port, on every scheme', () => {
    for (const base of ['s7://plc', 's7://[::1]', 'freeport+tcp://gw']) {
      expect(urlError(`${base}:99999`).message, base).to.include('port 99999 is out of range (1–65535)');
      expect(urlError(`${base}:65536?timeout=5`).message, base).to.include('port 65536 is out of range');
      expect(urlError(`${base}:12ab`).message, base).to.include('port "12ab" is not a number');
    }
    expect(urlError('s7://plc:0').message).to.include('port 0 is out of range (1–65535)');
    expect(urlError('freeport+tcp://gw:0').message).to.include('port 0 is out of range');
    // FETCH/WRITE takes its ports as parameters, whatever the number.
    expect(urlError('fetchwrite://h:99999').message).to.include('?fetchPort=');
    expect(urlError('s7://plc:99999').message).to.not.include('not a URL');
    expect(urlError('s7 plc').message).to.include('not a URL');
  });
});

describe('url: formatUrl and endpointKey', () => {
  const urls = [
    's7://192.168.0.2?rack=0&slot=1',
    's7://plc:1102?localTsap=1000&remoteTsap=2000&type=basic&pdu=240&timeout=100',
    's7://plc?rack=0&slot=1&maxItems=60',
    's7://192.168.0.2?rack=0&slot=2&control=true&readOnly=true',
    'fetchwrite://10.0.0.5?fetchPort=2000&writePort=2001',
    'fetchwrite://10.0.0.5?port=2000&dbUnit=byte&readOnly=true',
    'freeport:///dev/ttyUSB0?baud=9600',
    'freeport://COM3?baud=19200&parity=even&retries=5&allow=ST5,ST6',
    'freeport+tcp://gw:4001?timeout=500',
  ];
  for (const u of urls) {
    it(`round-trips ${u}`, () => {
      expect(formatUrl(parseUrl(u))).to.equal(u);
      expect(parseUrl(formatUrl(parseUrl(u)))).to.deep.equal(parseUrl(u));
    });
  }

  it('gives the same key to URLs that reach the same connection', () => {
    expect(endpointKey(parseUrl('s7://PLC?rack=0&slot=1&timeout=100'))).to.equal(endpointKey(parseUrl('s7://plc:102')));
    expect(endpointKey(parseUrl('s7://plc?slot=2'))).to.not.equal(endpointKey(parseUrl('s7://plc?slot=1')));
  });

  it('knows loopback hosts', () => {
    expect(isLoopback(parseUrl('s7://127.0.0.1'))).to.equal(true);
    expect(isLoopback(parseUrl('s7://[::1]'))).to.equal(true);
    expect(isLoopback(parseUrl('s7://192.168.0.1'))).to.equal(false);
    expect(isLoopback(parseUrl('freeport:///dev/ttyUSB0'))).to.equal(false);
  });
});

describe('url: a host that does not resolve', () => {
  // RFC 6761: names under .invalid never resolve, with or without a DNS server (EAI_AGAIN when none answers).
  for (const url of ['s7://plc.invalid', 'fetchwrite://plc.invalid?port=2000', 'freeport+tcp://plc.invalid:4001']) {
    it(`${url.split(':')[0]}: connect() fails with CONNECT_FAILED naming the host, in words`, async () => {
      const err = (await connect(`${url}${url.includes('?') ? '&' : '?'}timeout=3000`).catch((e: unknown) => e)) as PlcError;
      expect(err).to.be.instanceOf(PlcError);
      expect(err.code).to.equal('CONNECT_FAILED');
      expect(err.message).to.include('the host name "plc.invalid"');
      expect(err.message).to.match(/does not resolve \(ENOTFOUND\)|could not be looked up \(EAI_AGAIN/);
      expect(err.message).to.include("use the PLC's IP address");
    });
  }
});
