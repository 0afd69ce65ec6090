import { expect } from 'chai';
import fc from 'fast-check';
import { PlcError, ProtocolError } from '../lib/errors';
import { computeChecksum, decodeReply, decodeRequest, encodeReply, encodeRequest, readRequest, writeRequest } from '../lib/freeport/codec';
import { FreeportParser } from '../lib/freeport/parser';
import { defineProfile, DEFAULT_FREEPORT_PROFILE, replyLength, requestLength } from '../lib/freeport/profile';

const ascii = (s: string) => Buffer.from(s, 'latin1');
const text = (b: Buffer) => b.toString('latin1');
const E627A1C3 = Buffer.from([0xe6, 0x27, 0xa1, 0xc3]);

describe('freeport codec (docs/protocols.md, "S7-200 freeport")', () => {
  describe('the default frame profile (docs/protocols.md)', () => {
    it('writes E6 27 A1 C3 to station 5 as exactly qR0504E627A1C325Q', () => {
      expect(text(encodeRequest(writeRequest(5, E627A1C3)))).to.equal('qR0504E627A1C325Q');
      expect(requestLength(DEFAULT_FREEPORT_PROFILE)).to.equal(17);
    });

    it('reads station 5 with DT W, LE 04 and a zero DU', () => {
      // XOR of "W050400000000" = 0x56
      expect(text(encodeRequest(readRequest(5)))).to.equal('qW05040000000056Q');
    });

    it('decodes the write it encodes, field by field', () => {
      const req = decodeRequest(ascii('qR0504E627A1C325Q'));
      expect(req).to.deep.equal({ command: 'write', station: 5, length: 4, data: E627A1C3 });
    });

    it('writes fewer than 4 bytes as LE < 4 with DU padded by zeros', () => {
      const frame = text(encodeRequest(writeRequest(0x1f, Buffer.from([0x12, 0x34]))));
      expect(frame.slice(0, 14)).to.equal('qR1F0212340000');
      expect(decodeRequest(ascii(frame)).length).to.equal(2);
    });

    it('encodes and decodes a station reply: q DU(8) FC(2) Q, FC = XOR of the DU characters', () => {
      // XOR of "E627A1C3" = 0x76
      expect(text(encodeReply({ data: E627A1C3 }))).to.equal('qE627A1C376Q');
      expect(decodeReply(ascii('qE627A1C376Q'))).to.deep.equal({ data: E627A1C3 });
      expect(decodeReply(ascii('qe627a1c3' + '56Q')).data).to.deep.equal(E627A1C3); // lower case hex, its own FC
      expect(replyLength(DEFAULT_FREEPORT_PROFILE)).to.equal(12);
    });

    it('rejects a reply with a bad checksum, bad framing or non-hex DU with ProtocolError', () => {
      expect(() => decodeReply(ascii('qE627A1C377Q'))).to.throw(
        ProtocolError,
        /checksum mismatch: frame carries 77, its characters give 76/,
      );
      expect(() => decodeReply(ascii('qE627A1C376X'))).to.throw(ProtocolError, /not framed/);
      expect(() => decodeReply(ascii('qE627A1CZ76Q'))).to.throw(ProtocolError, /not hex/);
      expect(() => decodeReply(ascii('qE627A1C3Q'))).to.throw(ProtocolError, /10 characters \(expected 12\)/);
    });

    it('rejects requests with an unknown command or LE beyond the data area', () => {
      expect(() => decodeRequest(ascii('qX0504E627A1C325Q'))).to.throw(ProtocolError, /unknown command "X"/);
      const tooLong = 'R0505E627A1C3';
      const fcHex = computeChecksum('xor-chars', tooLong, 1).toString(16).toUpperCase().padStart(2, '0');
      expect(() => decodeRequest(ascii(`q${tooLong}${fcHex}Q`))).to.throw(ProtocolError, /LE 5 exceeds/);
    });

    it('refuses to encode what does not fit the fields', () => {
      expect(() => encodeRequest(readRequest(256))).to.throw(PlcError, /station 256 does not fit 2 hex characters/);
      expect(() => writeRequest(5, Buffer.alloc(5))).to.throw(PlcError, /1–4 bytes, not 5/);
      expect(() => writeRequest(5, Buffer.alloc(0))).to.throw(PlcError, /1–4 bytes, not 0/);
    });
  });

  describe('erratum: the circulated example write frame fails its own checksum rule', () => {
    // The circulated paper says writing E6 27 A1 C3 to station 5 is sent as "q W 0 5 0 4 E 6 2 7 A 1 C 3 2 D Q" (docs/protocols.md, corrections).
    const documentExample = 'qW0504E627A1C32DQ';

    it('its FC 2D is not the XOR of DT..DU (that is 20), nor any other common rule', () => {
      const covered = 'W0504E627A1C3';
      expect(computeChecksum('xor-chars', covered, 1)).to.equal(0x20);
      expect(computeChecksum('sum-mod-256', covered, 1)).to.equal(0xec);
      expect(computeChecksum('xor-bytes', covered, 1)).to.equal(0xf5);
      expect(computeChecksum('xor-chars', `q${covered}`, 1)).to.equal(0x51); // not even with the start character
      expect(() => decodeRequest(ascii(documentExample))).to.throw(ProtocolError, /frame carries 2D, its characters give 20/);
    });

    it('is described as a write but uses W, which the same description defines as read (57H = read)', () => {
      const corrected = `qW0504E627A1C320Q`; // the checksum fixed, W kept
      expect(decodeRequest(ascii(corrected)).command).to.equal('read');
    });

    it('the write it describes, under its own rules, is qR0504E627A1C325Q (XOR 0x25)', () => {
      expect(computeChecksum('xor-chars', 'R0504E627A1C3', 1)).to.equal(0x25);
      expect(decodeRequest(ascii('qR0504E627A1C325Q')).command).to.equal('write');
    });
  });

  describe('checksum kinds and custom profiles', () => {
    it('computes each kind over the same characters', () => {
      expect(computeChecksum('xor-chars', 'R0504E627A1C3', 1)).to.equal(0x25);
      expect(computeChecksum('xor-bytes', 'R0504E627A1C3', 1)).to.equal(0x52 ^ 0x05 ^ 0x04 ^ 0xe6 ^ 0x27 ^ 0xa1 ^ 0xc3);
      expect(computeChecksum('sum-mod-256', 'E627A1C3')).to.equal(0xcc);
      expect(computeChecksum('none', 'E627A1C3')).to.equal(0);
    });

    it('builds frames of a custom profile: other characters, wider fields, sum checksum, echoed address', () => {
      const p = defineProfile({
        start: ':',
        end: '\r',
        readCommand: 'r',
        writeCommand: 'w',
        addressWidth: 4,
        dataBytes: 2,
        checksum: 'sum-mod-256',
        replyEchoesAddress: true,
      });
      const req = text(encodeRequest(writeRequest(0x1234, Buffer.from([0xab, 0xcd]), p), p));
      const body = 'w123402ABCD';
      const sum = [...body].reduce((a, c) => a + c.charCodeAt(0), 0) & 0xff;
      expect(req).to.equal(`:${body}${sum.toString(16).toUpperCase().padStart(2, '0')}\r`);
      expect(decodeRequest(ascii(req), p)).to.deep.include({ command: 'write', station: 0x1234, length: 2 });
      const reply = encodeReply({ station: 0x1234, data: Buffer.from([0xab, 0xcd]) }, p);
      expect(decodeReply(reply, p)).to.deep.equal({ station: 0x1234, data: Buffer.from([0xab, 0xcd]) });
    });

    it('has no FC at all with checksum none', () => {
      const p = defineProfile({ checksum: 'none' });
      expect(text(encodeRequest(writeRequest(5, E627A1C3, p), p))).to.equal('qR0504E627A1C3Q');
      expect(decodeReply(ascii('qE627A1C3Q'), p).data).to.deep.equal(E627A1C3);
    });

    it('refuses a profile whose characters could be confused', () => {
      expect(() => defineProfile({ start: 'A' })).to.throw(PlcError, /start must not be a hex digit/);
      expect(() => defineProfile({ end: 'q' })).to.throw(PlcError, /end must differ from start/);
      expect(() => defineProfile({ writeCommand: 'W' })).to.throw(PlcError, /must differ from readCommand/);
      expect(() => defineProfile({ readCommand: 'QQ' })).to.throw(PlcError, /one ASCII character/);
      expect(() => defineProfile({ checksum: 'crc' as never })).to.throw(PlcError, /checksum must be one of/);
      expect(() => defineProfile({ dataBytes: 20, lengthWidth: 1 })).to.throw(PlcError, /too narrow/);
    });
  });
});

describe('freeport stream parser', () => {
  const reply = ascii('qE627A1C376Q');
  const request = ascii('qR0504E627A1C325Q');

  it('finds the frame whatever the split point', () => {
    const stream = Buffer.concat([reply, reply]);
    for (let cut = 0; cut <= stream.length; cut++) {
      const parser = new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'reply');
      const frames = [...parser.push(stream.subarray(0, cut)), ...parser.push(stream.subarray(cut))];
      expect(
        frames.map((f) => f.kind),
        `cut at ${cut}`,
      ).to.deep.equal(['reply', 'reply']);
    }
  });

  it('feeds byte by byte', () => {
    const parser = new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'request');
    const frames = [...request].flatMap((b) => parser.push(Buffer.from([b])));
    expect(frames).to.have.length(1);
    expect(frames[0]).to.deep.include({ kind: 'request' });
  });

  it('resynchronises after noise, a truncated frame and garbage', () => {
    const parser = new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'reply');
    const frames = parser.push(
      Buffer.concat([
        Buffer.from([0x00, 0xff, 0x71, 0x13]), // noise, a stray start character
        ascii('qE627A'), // a reply cut off by a station reset
        reply,
        ascii('Qxyz\r\n'),
        reply,
      ]),
    );
    expect(frames.map((f) => f.kind)).to.deep.equal(['reply', 'reply']);
    expect(parser.skippedBytes).to.be.greaterThan(0);
    expect(parser.buffered).to.equal(0);
  });

  it("ignores the master's own echo and other stations' traffic in the other direction", () => {
    const replies = new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'reply');
    expect(replies.push(Buffer.concat([request, reply]))).to.have.length(1);
    const requests = new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'request');
    expect(requests.push(Buffer.concat([reply, request])).map((f) => f.kind)).to.deep.equal(['request']);
  });

  it('reports a frame with a flipped bit as corrupt instead of a value', () => {
    const bad = Buffer.from(reply);
    bad[3] ^= 0x01; // '2' → '3': still hex, so only the checksum can catch it
    const frames = new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'reply').push(bad);
    expect(frames).to.have.length(1);
    expect(frames[0]!.kind).to.equal('corrupt');
    if (frames[0]!.kind === 'corrupt') expect(frames[0]!.error.message).to.match(/checksum mismatch/);
  });

  it('never throws on arbitrary bytes, in arbitrary chunks, and cuts only whole-length frames', () => {
    fc.assert(
      fc.property(fc.array(fc.uint8Array({ maxLength: 40 }), { maxLength: 10 }), fc.constantFrom('request', 'reply'), (chunks, dir) => {
        const parser = new FreeportParser(DEFAULT_FREEPORT_PROFILE, dir as 'request' | 'reply');
        const length = dir === 'request' ? 17 : 12;
        for (const c of chunks) for (const f of parser.push(Buffer.from(c))) expect(f.raw.length).to.equal(length);
        expect(parser.buffered).to.be.lessThan(length);
      }),
      { numRuns: 500 },
    );
  });

  it('always finds a valid frame after any garbage (the start character fits no other position)', () => {
    const alphabet = fc.constantFrom(...'qQWR0123456789ABCDEFabcdef\x00\xff\r\n'.split(''));
    fc.assert(
      fc.property(
        fc.array(alphabet, { maxLength: 60 }),
        fc.uint8Array({ minLength: 4, maxLength: 4 }),
        fc.integer({ min: 0, max: 255 }),
        (garbage, data, station) => {
          const parser = new FreeportParser(DEFAULT_FREEPORT_PROFILE, 'request');
          const frame = encodeRequest(writeRequest(station, Buffer.from(data)));
          const frames = parser.push(Buffer.concat([ascii(garbage.join('')), frame]));
          const last = frames[frames.length - 1];
          expect(last?.kind).to.equal('request');
          if (last?.kind === 'request') expect(last.request).to.deep.include({ station, command: 'write' });
        },
      ),
      { numRuns: 500 },
    );
  });

  it('round-trips every request and reply under every checksum kind', () => {
    fc.assert(
      fc.property(
        fc.constantFrom('xor-chars', 'xor-bytes', 'sum-mod-256', 'none' as const),
        fc.integer({ min: 0, max: 255 }),
        fc.uint8Array({ minLength: 1, maxLength: 4 }),
        (checksum, station, data) => {
          const p = defineProfile({ checksum: checksum as 'xor-chars' });
          const req = writeRequest(station, Buffer.from(data), p);
          expect(decodeRequest(encodeRequest(req, p), p)).to.deep.equal(req);
          const padded = Buffer.alloc(4);
          Buffer.from(data).copy(padded);
          expect(decodeReply(encodeReply({ data: padded }, p), p).data).to.deep.equal(padded);
        },
      ),
      { numRuns: 300 },
    );
  });
});
