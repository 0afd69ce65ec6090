/** `plcwire sparkplug`'s command line: what it takes and the usage error each mistake gets (lib/cli/sparkplug-args.ts). */
import { expect } from 'chai';
import { parseArgs, UsageError } from '../lib/cli/args';
import { SPARKPLUG_FLAGS, sparkplugOptions } from '../lib/cli/sparkplug-args';

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
      'mqtts://backup:8883',
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
    expect(o.brokers).to.deep.equal(['mqtt://127.0.0.1:1883', 'mqtts://backup:8883']);
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

  it('refuses a PLC URL it cannot read with the URL error', () => {
    expect(() => parse('--broker', 'mqtt://h', '--group', 'G', '--node', 'E', '--device', 'L=nope://h')).to.throw(/nope/);
  });
});
