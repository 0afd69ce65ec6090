/**
 * The CPU's identity over S7CommPlus (lib/s7plus/codec/identity.ts): the
 * device string of ServerSessionVersion as the s7commplus package (MIT)
 * shows it from real PLCs and PLCSIM (legitimation.py, connection.py,
 * server.py), and the one our simulator writes for a profile, decoded back
 * from the bytes of its CreateObject answer.
 */
import { expect } from 'chai';
import { deviceString, formatDeviceString, parseDeviceString } from '../lib/s7plus/codec/identity';
import { decodePValue } from '../lib/s7plus/codec/pvalue';
import { DataType, Ids } from '../lib/s7plus/constants';
import { encodeUVlq32 } from '../lib/s7plus/codec/vlq';

/** A ServerSessionVersion as a CPU sends it: Struct 314 with the protocol version (315) and the device string (319). */
function sessionVersion(device: string): Buffer {
  const id = Buffer.alloc(4);
  id.writeUInt32BE(Ids.SessionVersionStruct);
  const text = Buffer.from(device, 'utf8');
  return Buffer.concat([
    Buffer.from([0x00, DataType.Struct]),
    id,
    encodeUVlq32(315),
    Buffer.from([0x00, DataType.UDInt]),
    encodeUVlq32(3),
    encodeUVlq32(Ids.SessionVersionSystemPaomString),
    Buffer.from([0x00, DataType.WString]),
    encodeUVlq32(text.length),
    text,
    Buffer.from([0x00]),
  ]);
}

describe('S7CommPlus identity (the device string)', () => {
  it('reads order code and firmware of the strings public sources show: an S7-1200 with its trailing space, an S7-1500, PLCSIM Advanced', () => {
    expect(parseDeviceString('1;6ES7 215-1BG40-0XB0 ;V4.2')).to.deep.equal({
      device: '1;6ES7 215-1BG40-0XB0 ;V4.2',
      orderCode: '6ES7 215-1BG40-0XB0',
      firmware: 'V4.2',
    });
    expect(parseDeviceString('1;6ES7 512-1CK01-0AB0;V2.9')).to.include({ orderCode: '6ES7 512-1CK01-0AB0', firmware: 'V2.9' });
    expect(parseDeviceString('1;6ES7 SIM-01500-APLC;S4.1')).to.include({ orderCode: '6ES7 SIM-01500-APLC', firmware: 'S4.1' });
  });

  it('leaves out what a malformed string does not say, and never throws', () => {
    expect(parseDeviceString('garbage')).to.include({ orderCode: undefined, firmware: undefined });
    expect(parseDeviceString('1;;V1.0')).to.include({ orderCode: undefined, firmware: 'V1.0' });
    expect(parseDeviceString('1;6ES7 516-3AN02-0AB0;latest')).to.include({ orderCode: '6ES7 516-3AN02-0AB0', firmware: undefined });
  });

  it('finds the device string in a ServerSessionVersion struct; a UDInt version (the s7commplus emulator) or an oversized string gives none', () => {
    const decoded = decodePValue(sessionVersion('1;6ES7 516-3AN02-0AB0 ;V3.1')).value;
    expect(deviceString(decoded)).to.equal('1;6ES7 516-3AN02-0AB0 ;V3.1');
    expect(deviceString({ flags: 0, type: DataType.UDInt, value: 3 })).to.equal(undefined);
    expect(deviceString(undefined)).to.equal(undefined);
    expect(deviceString(decodePValue(sessionVersion(`1;${'X'.repeat(300)};V1.0`)).value)).to.equal(undefined);
  });

  it("writes a profile's identity as a CPU does: the firmware cut to major.minor, which clients match as a whole field", () => {
    expect(formatDeviceString('6ES7 516-3AN02-0AB0', 'V3.1.0')).to.equal('1;6ES7 516-3AN02-0AB0 ;V3.1');
    expect(formatDeviceString('6ES7 214-1AG40-0XB0', 'V4.7.0')).to.equal('1;6ES7 214-1AG40-0XB0 ;V4.7');
    expect(parseDeviceString(formatDeviceString('6ES7 214-1AG40-0XB0', 'V4.7.0'))).to.include({
      orderCode: '6ES7 214-1AG40-0XB0',
      firmware: 'V4.7',
    });
  });
});
