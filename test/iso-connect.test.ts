/** lib/iso/: the COTP connection request with TSAPs of any length. */
import { expect } from 'chai';
import { ValueError } from '../lib/errors';
import { decodeCotp, encodeConnectionRequest } from '../lib/iso/cotp';
import { hex, show } from './fixtures/s7';

/** S7CommPlus's called TSAP: s7commplus (MIT), s7commplus/protocol.py, S7COMMPLUS_REMOTE_TSAP. */
const ROOT_HMI = Buffer.from('SIMATIC-ROOT-HMI', 'ascii');

/**
 * The CR s7commplus sends (s7commplus (MIT), s7commplus/transport.py, _build_cotp_cr): calling TSAP 0x0600
 * (2 bytes), called TSAP "SIMATIC-ROOT-HMI" (16 bytes), then the TPDU size 0x0A; LI 31, TPKT length 36.
 */
const ROOT_HMI_CR = hex(`03 00 00 24 | 1F E0 00 00 00 01 00 | C1 02 06 00 | C2 10 ${ROOT_HMI.toString('hex')} | C0 01 0A`);

describe('ISO-on-TCP (lib/iso/)', () => {
  describe('connection request with TSAPs of any length', () => {
    it('encodes the CR with the TSAP SIMATIC-ROOT-HMI byte for byte as s7commplus sends it', () => {
      const frame = encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x0600, calledTsap: ROOT_HMI, tpduSize: 0x0a });
      expect(show(frame)).to.equal(show(ROOT_HMI_CR));
      // A TSAP that is not 2 bytes long decodes as -1 (a CotpConnection's TSAPs are numbers), the rest as sent.
      expect(decodeCotp(frame)).to.deep.equal({
        type: 'CR',
        sourceRef: 1,
        destinationRef: 0,
        callingTsap: 0x0600,
        calledTsap: -1,
        tpduSize: 0x0a,
      });
    });

    it('a TSAP given as 2 bytes is the same frame as the number', () => {
      const asBytes = encodeConnectionRequest({
        sourceRef: 1,
        callingTsap: Buffer.from([0x10, 0x00]),
        calledTsap: Buffer.from([0x03, 0x01]),
        tpduSize: 0x0a,
      });
      expect(show(asBytes)).to.equal(
        show(encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x1000, calledTsap: 0x0301, tpduSize: 0x0a })),
      );
    });

    it('refuses an empty TSAP and one longer than a parameter can carry (ValueError)', () => {
      expect(() => encodeConnectionRequest({ sourceRef: 1, callingTsap: 0x0600, calledTsap: Buffer.alloc(0), tpduSize: 0x0a })).to.throw(
        ValueError,
        /called TSAP.*0 bytes/,
      );
      expect(() => encodeConnectionRequest({ sourceRef: 1, callingTsap: Buffer.alloc(256), calledTsap: 1, tpduSize: 0x0a })).to.throw(
        ValueError,
        /calling TSAP.*256 bytes/,
      );
      // Two TSAPs of 255 bytes fit no length indicator (at most 254).
      expect(() =>
        encodeConnectionRequest({ sourceRef: 1, callingTsap: Buffer.alloc(255), calledTsap: Buffer.alloc(255), tpduSize: 0x0a }),
      ).to.throw(ValueError, /length indicator/);
    });
  });
});
