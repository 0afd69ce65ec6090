/**
 * `npm run fuzz [-- inputs]`: at least 1,000,000 mutated inputs per decoder
 * (default), outside the test suite. Prints a table; exits 1 on any finding
 * (an exception that is not one of our typed errors).
 */
import { parseAddress } from '../../lib/address';
import { FrameReader } from '../../lib/link/framer';
import {
  checkTpkt,
  decodeCotp,
  decodeS7,
  s7AnswerRef,
  scanReadAck,
  encodeReadResponse,
  encodeSetupAck,
  encodeWriteResponse,
  encodeErrorAck,
  encodeReadRequest,
  encodeWriteRequest,
} from '../../lib/s7/codec';
import { decodeTag } from '../../lib/values';
import { fuzz, type FuzzTarget } from './engine';
import { s7plusAlarmTargets } from './s7plus-alarm-targets';
import { s7plusTargets } from './s7plus-targets';
import { symbolTargets } from './symbol-targets';
import { extraTargets } from './targets';
import { alarmTargets } from './alarm-targets';
import { cyclicTargets } from './cyclic-targets';
import { sparkplugTargets } from './sparkplug-targets';

const inputs = Number(process.argv[2] ?? 1_000_000);

const s7Seeds = [
  Buffer.from('0300001611D00001001100C0010AC1021000C2020301', 'hex'),
  encodeSetupAck(1, { maxAmqCalling: 3, maxAmqCalled: 3, pduSize: 240 }),
  encodeReadResponse(2, [
    { returnCode: 0xff, transportSize: 4, data: Buffer.from('0102', 'hex') },
    { returnCode: 0x0a, transportSize: 0, data: Buffer.alloc(0) },
    { returnCode: 0xff, transportSize: 3, data: Buffer.of(1) },
  ]),
  encodeWriteResponse(3, [0xff, 0x05]),
  encodeErrorAck(4, 0x81, 0x04),
  encodeReadRequest(5, [{ area: 0x84, dbNumber: 1, transportSize: 2, count: 4, address: 0 }]),
  encodeWriteRequest(6, [{ area: 0x84, dbNumber: 1, transportSize: 2, count: 1, address: 8, dataTransportSize: 4, data: Buffer.of(9) }]),
];

const valueTags = [
  'DB1,S0.20',
  'DB1,WSTRING0.8',
  'DB1.DBB0:DTL',
  'DB1.DBB0:DATE_AND_TIME',
  'DB1.DBW0:S5TIME',
  'DB1.DBX0.3:BOOL[9]',
  'DB1.DBD0:REAL[3]',
  'C0',
  'DB1.DBB0:LINT',
].map(parseAddress);

const targets: FuzzTarget[] = [
  {
    name: 'S7 decodeS7 (whole frames)',
    seeds: s7Seeds,
    run: (b) => void decodeS7(b),
  },
  {
    name: 'S7 decodeCotp',
    seeds: s7Seeds,
    run: (b) => void decodeCotp(b),
  },
  {
    name: 'S7 TPKT framer (stream)',
    seeds: [Buffer.concat(s7Seeds)],
    run: (b) => {
      const reader = new FrameReader(checkTpkt, 70_000);
      for (const frame of reader.push(b)) {
        try {
          decodeS7(frame);
        } catch (err) {
          if (!(err instanceof Error) || !('code' in err)) throw err;
        }
      }
    },
  },
  {
    // The client's read path must accept exactly what decodeS7 accepts, at the same offsets.
    name: 'S7 in-place read ack (client)',
    seeds: s7Seeds,
    run: (b) => {
      const count = b[20] ?? 0;
      const table = { code: new Uint8Array(count), start: new Int32Array(count), length: new Int32Array(count) };
      const ref = s7AnswerRef(b);
      const taken = scanReadAck(b, count, table, 0);
      let m: ReturnType<typeof decodeS7> | undefined;
      try {
        m = decodeS7(b);
      } finally {
        // Replaces decodeS7's own error on purpose: the disagreement is the finding.
        // eslint-disable-next-line no-unsafe-finally
        if (taken && m === undefined) throw new Error('scanReadAck took a frame decodeS7 refuses');
      }
      if (ref >= 0 && ref !== m.pduRef) throw new Error(`s7AnswerRef ${ref}, decodeS7 ${m.pduRef}`);
      if (taken !== (m.kind === 'read-ack' && m.items.length === count && b[4] === 2))
        throw new Error('scanReadAck and decodeS7 disagree on taking it');
      if (m.kind !== 'read-ack' || !taken) return;
      m.items.forEach((item, i) => {
        if (
          table.code[i] !== item.returnCode ||
          table.length[i] !== item.data.length ||
          table.start[i] !== item.data.byteOffset - b.byteOffset
        ) {
          throw new Error(`item ${i} located differently`);
        }
      });
    },
  },
  {
    name: 'value decoders (9 types)',
    seeds: [Buffer.alloc(32)],
    run: (b) => {
      for (const tag of valueTags) if (b.length >= tag.byteLength) decodeTag(tag, b);
    },
  },
  {
    name: 'address parser',
    seeds: ['DB1,INT2', 'DB1.DBD4:REAL', 'DB1.DBB0:STRING[30][2]', 'MW10:INT', 'V10.1', 'PIW256', 'T3:TIMER[4]'].map((s) =>
      Buffer.from(s, 'latin1'),
    ),
    run: (b) => void parseAddress(b.toString('latin1')),
  },
  ...extraTargets(),
  ...symbolTargets(),
  ...s7plusTargets(),
  ...s7plusAlarmTargets(),
  ...alarmTargets(),
  ...cyclicTargets(),
  ...sparkplugTargets(),
];

const results = targets.map((t) => fuzz(t, inputs));
const pad = (s: string | number, n: number) => String(s).padEnd(n);
console.log(`${pad('decoder', 34)}${pad('inputs', 11)}${pad('accepted', 10)}${pad('typed errors', 14)}${pad('findings', 10)}inputs/s`);
for (const r of results) {
  console.log(
    `${pad(r.name, 34)}${pad(r.inputs, 11)}${pad(r.accepted, 10)}${pad(r.typedErrors, 14)}${pad(r.findingCount, 10)}${Math.round(r.inputs / (r.ms / 1000))}`,
  );
}
const findings = results.flatMap((r) => r.findings.map((f) => ({ decoder: r.name, ...f })));
for (const f of findings) console.error(`FINDING in ${f.decoder}: input ${f.input}\n${f.error}\n`);
process.exitCode = findings.length > 0 ? 1 : 0;
