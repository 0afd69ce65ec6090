/** `plcwire sparkplug`'s command line: what it takes and the usage error each mistake gets (lib/cli/sparkplug-args.ts). */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { parseArgs, UsageError } from '../lib/cli/args';
import { SPARKPLUG_FLAGS, sparkplugOptions } from '../lib/cli/sparkplug-args';
import { skipBecause } from './support/skip';

const parse = (...argv: string[]) => sparkplugOptions(parseArgs(argv, [...SPARKPLUG_FLAGS, 'interval', 'symbols', 'db'], []));
const BASE = ['--broker', 'mqtt://127.0.0.1:1883', '--group', 'Plant', '--node', 'Edge1', '--device', 'Line1=s7://127.0.0.1:10102'];

function usage(argv: string[], message: RegExp): void {
  expect(() => parse(...argv))
    .to.throw(UsageError)
    .with.property('message')
    .that.matches(message);
}

describe('plcwire sparkplug: the command line', () => {
  it('takes brokers in order, the ids, each device with its tags and writable tags, and the defaults', () => {
    const o = parse(
      ...BASE,
      '--broker',
      'mqtt://backup:1883',
      '--device',
      'Line2=s7plus://127.0.0.1:10103?insecure=true',
      '--tags',
      'Line1:"Tank".Level,DB1.DBW2:INT',
      '--tags',
      'Line1:MW4',
      '--writable',
      'Line1:MW4',
      '--primary-host',
      'SCADA',
    );
    expect(o.brokers).to.deep.equal(['mqtt://127.0.0.1:1883', 'mqtt://backup:1883']);
    expect(o.mqtt).to.deep.equal({});
    expect(o).to.include({ group: 'Plant', node: 'Edge1', primaryHost: 'SCADA', interval: 1000, buffer: 10_000 });
    expect(o.devices.map((d) => d.name)).to.deep.equal(['Line1', 'Line2']);
    expect(o.devices[0]).to.include({ url: 's7://127.0.0.1:10102' });
    expect(o.devices[0]!.tags).to.deep.equal(['"Tank".Level', 'DB1.DBW2:INT', 'MW4']);
    expect(o.devices[0]!.writable).to.deep.equal(['MW4']);
    expect(o.devices[1]!.tags).to.equal(undefined);
    expect(o.devices[1]!.endpoint.protocol).to.equal('s7plus');
  });

  it('takes --interval, --buffer and --state-dir', () => {
    const o = parse(...BASE, '--interval', '100', '--buffer', '0', '--state-dir', '/var/lib/plcwire');
    expect(o).to.include({ interval: 100, buffer: 0, stateDir: '/var/lib/plcwire' });
  });

  describe("the broker's login and TLS", () => {
    const TLS = ['--broker', 'mqtts://broker.plant:8883', '--group', 'Plant', '--node', 'Edge1', '--device', 'Line1=s7://127.0.0.1:10102'];
    let dir: string;
    before(() => (dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-mqtt-'))));
    after(() => fs.rmSync(dir, { recursive: true, force: true }));
    const file = (name: string, text: string) => {
      const f = path.join(dir, name);
      fs.writeFileSync(f, text);
      return f;
    };
    const PEM = '-----BEGIN CERTIFICATE-----\nMIIB\n-----END CERTIFICATE-----\n';

    it('takes --mqtt-user with the first line of --mqtt-password-file, or PLCWIRE_MQTT_PASSWORD, and --mqtt-ca/--mqtt-cert/--mqtt-key as PEM', () => {
      const o = parse(
        ...TLS,
        '--mqtt-user',
        'edge1',
        '--mqtt-password-file',
        file('pw', 'Secret-1\nignored\n'),
        '--mqtt-ca',
        file('ca.pem', PEM),
        '--mqtt-cert',
        file('c.pem', PEM),
        '--mqtt-key',
        file('k.pem', '-----BEGIN PRIVATE KEY-----\nx\n-----END PRIVATE KEY-----\n'),
      );
      expect(o.mqtt).to.include({ username: 'edge1', password: 'Secret-1' });
      expect(String(o.mqtt.ca)).to.equal(PEM);
      expect(String(o.mqtt.cert)).to.equal(PEM);
      const env = process.env['PLCWIRE_MQTT_PASSWORD'];
      process.env['PLCWIRE_MQTT_PASSWORD'] = 'From-Env';
      try {
        expect(parse(...TLS, '--mqtt-user', 'edge1').mqtt).to.deep.equal({ username: 'edge1', password: 'From-Env' });
      } finally {
        if (env === undefined) delete process.env['PLCWIRE_MQTT_PASSWORD'];
        else process.env['PLCWIRE_MQTT_PASSWORD'] = env;
      }
    });

    it('refuses a user or password in the broker URL without repeating the password, and every other mistake by name', () => {
      const err = (() => {
        try {
          parse('--broker', 'mqtts://edge1:Top-Secret@broker.plant:8883', ...TLS.slice(2));
        } catch (e) {
          return e as Error;
        }
        return undefined;
      })();
      expect(err).to.be.instanceOf(UsageError);
      expect(err!.message)
        .to.match(/"mqtts:\/\/edge1:\*\*\*@broker\.plant:8883": no user or password in the URL/)
        .and.not.include('Top-Secret');
      usage([...BASE, '--broker', 'mqtts://b:8883'], /mix mqtts:\/\/ \(wss:\/\/\) and mqtt:\/\/.*fall back to plain text/);
      usage([...BASE, '--mqtt-ca', file('ca2.pem', PEM)], /--mqtt-ca, --mqtt-cert and --mqtt-key are for mqtts:\/\//);
      usage([...TLS, '--mqtt-cert', file('c2.pem', PEM)], /--mqtt-cert and --mqtt-key go together/);
      usage([...TLS, '--mqtt-ca', file('not.pem', 'hello')], /--mqtt-ca .*not\.pem: not a PEM file/);
      usage([...TLS, '--mqtt-ca', path.join(dir, 'missing.pem')], /--mqtt-ca: .*missing\.pem/);
      usage([...TLS, '--mqtt-password-file', file('pw2', 'Secret-2\n')], /gives a password but no --mqtt-user/);
      usage(
        [...TLS, '--mqtt-user', 'u', '--mqtt-password-file', file('empty', '\n')],
        /--mqtt-password-file .*empty: its first line is empty/,
      );
    });
  });

  it('refuses each mistake with a usage error that names the option and the value', () => {
    usage(['--group', 'G', '--node', 'E', '--device', 'L=s7://h'], /at least one --broker/);
    usage(['--broker', 'http://h', '--group', 'G', '--node', 'E', '--device', 'L=s7://h'], /--broker "http:\/\/h": the scheme/);
    usage(
      ['--broker', 'mqtt://h', '--group', 'G/1', '--node', 'E', '--device', 'L=s7://h'],
      /--group "G\/1": a Sparkplug id cannot hold "\/"/,
    );
    usage(['--broker', 'mqtt://h', '--group', 'G', '--device', 'L=s7://h'], /--node needs a value/);
    usage(['--broker', 'mqtt://h', '--group', 'G', '--node', 'E#'], /--node "E#"/);
    usage(['--broker', 'mqtt://h', '--group', 'G', '--node', 'E'], /at least one --device/);
    usage([...BASE, '--device', 'Line1=s7://other'], /--device Line1 is given twice/);
    usage([...BASE, '--device', 's7://h'], /--device "s7:\/\/h": give NAME=<plc url>/);
    usage([...BASE, '--tags', 'Line9:MW4'], /--tags "Line9:MW4": no --device Line9=<url> \(devices: Line1\)/);
    usage([...BASE, '--tags', 'Line1:MW4,'], /an empty tag/);
    usage([...BASE, '--tags', 'Line1:MW4', '--writable', 'Line1:MW6'], /--writable Line1:MW6: "MW6" is not one of the device's --tags/);
    usage([...BASE, '--interval', '5'], /--interval must be between 10 and 3600000/);
    usage([...BASE, '--primary-host', 'A+B'], /--primary-host "A\+B"/);
  });

  it("--alarms NAME publishes that device's alarms; --writable NAME:Alarms/Acknowledge stays whole and lets a host acknowledge", () => {
    const o = parse(
      ...BASE,
      '--device',
      'Line2=s7plus://127.0.0.1:10103?insecure=true',
      '--device',
      'Line3=s7://127.0.0.1:10104',
      '--tags',
      'Line1:MW4',
      '--alarms',
      'Line1',
      '--alarms',
      'Line2',
      '--writable',
      'Line1:MW4,Alarms/Acknowledge',
      '--writable',
      'Line2:Alarms/Acknowledge',
    );
    expect(o.devices.map((d) => [d.name, d.alarms, d.writable])).to.deep.equal([
      ['Line1', true, ['MW4', 'Alarms/Acknowledge']],
      ['Line2', true, ['Alarms/Acknowledge']],
      ['Line3', false, []],
    ]);
    expect(o.devices[0]!.tags).to.deep.equal(['MW4']);
  });

  it('refuses --alarms for an unknown device, or one whose protocol reports no alarms, and an acknowledge without --alarms', () => {
    usage([...BASE, '--alarms', 'Line9'], /^--alarms "Line9": no --device Line9=<url> \(devices: Line1\)$/);
    usage(
      [...BASE, '--device', 'CP=fetchwrite://127.0.0.1?fetchPort=2000&writePort=2001', '--alarms', 'CP'],
      /^--alarms CP: its PLC is reached over fetchwrite:\/\/, which reports no alarms \(s7:\/\/ or s7plus:\/\/ do\)$/,
    );
    usage(
      [...BASE, '--device', 'S200=freeport+tcp://127.0.0.1:4001', '--alarms', 'S200'],
      /^--alarms S200: .*freeport:\/\/, which reports no alarms/,
    );
    usage(
      [...BASE, '--writable', 'Line1:Alarms/Acknowledge'],
      /^--writable Line1:Alarms\/Acknowledge: the device publishes no alarms; give --alarms Line1 as well$/,
    );
  });

  describe('--buffer-dir', () => {
    let dir = '';
    before(() => (dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-spb-args-'))));
    after(() => fs.rmSync(dir, { recursive: true, force: true }));

    it('takes a directory this process may write', () => {
      expect(parse(...BASE, '--buffer-dir', dir).bufferDir).to.equal(dir);
      expect(parse(...BASE).bufferDir).to.equal(undefined);
    });

    it('refuses a missing directory and a file', () => {
      usage([...BASE, '--buffer-dir', path.join(dir, 'nope')], /^--buffer-dir ".*nope": no such directory$/);
      const file = path.join(dir, 'file');
      fs.writeFileSync(file, '');
      usage([...BASE, '--buffer-dir', file], /^--buffer-dir ".*file": not a directory$/);
    });

    it('refuses a directory this process may not write', function () {
      if (process.getuid?.() !== 0) {
        const locked = path.join(dir, 'locked');
        fs.mkdirSync(locked, { mode: 0o500 });
        return usage([...BASE, '--buffer-dir', locked], /^--buffer-dir ".*locked": this process may not write there$/);
      }
      // Root writes to any directory whatever its mode, but not into /proc/self (the kernel refuses it).
      if (!refusesWrite('/proc/self'))
        skipBecause(this, 'running as root, and /proc/self is writable here: no directory root may not write');
      usage([...BASE, '--buffer-dir', '/proc/self'], /^--buffer-dir "\/proc\/self": this process may not write there$/);
    });
  });

  it('refuses a PLC URL it cannot read with the URL error', () => {
    expect(() => parse('--broker', 'mqtt://h', '--group', 'G', '--node', 'E', '--device', 'L=nope://h')).to.throw(/nope/);
  });
});

function refusesWrite(dir: string): boolean {
  try {
    fs.accessSync(dir, fs.constants.W_OK | fs.constants.X_OK);
    return false;
  } catch {
    return true;
  }
}
