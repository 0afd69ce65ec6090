/**
 * The connection doctor's handshake steps (lib/s7/doctor/index.ts): TCP, the
 * COTP connection request and setup communication, on a raw socket with the
 * codec, so each answer (a COTP disconnect and its reason, silence, a
 * foreign protocol) can be told apart. A refused connection request is
 * followed by the usual addressings, to say which one the CPU accepts.
 */
import type * as net from 'node:net';
import { abortError, type PlcError } from '../../errors';
import { FrameReader } from '../../link/framer';
import type { S7Endpoint } from '../../url';
import { checkTpkt, decodeCotp, decodeS7, encodeConnectionRequest, encodeSetupCommunication } from '../codec';
import { REQUESTED_AMQ, TPDU_SIZE_CODE, headerError } from '../constants';
import { DR_CONGESTION, MAX_FRAME } from '../../iso/constants';
import { hex4 } from '../../values/text';
import { addressingOf, alternatives, type Addressing } from './families';
import { HINT } from './hints';
import type { StepContext } from './tags';

/** What the handshake steps use of the doctor's walk: its abort, its steps, its per-step timeout and its tracked sockets. */
export interface HandshakeContext extends Omit<StepContext, 'client'> {
  /** The URL's timeout, cut to what is left of the doctor's deadline. */
  stepTimeout(e: S7Endpoint): number;
  /** A TCP connection to the PLC, closed by the doctor at the end of the walk if not before. */
  tcp(e: S7Endpoint, address: string): Promise<net.Socket>;
}

export class Handshake {
  constructor(private readonly c: HandshakeContext) {}

  /** The tcp, cotp and setup steps, on a socket of their own (closed when they end). */
  async run(e: S7Endpoint, address: string): Promise<void> {
    const where = `${address}:${e.port}`;
    let socket: net.Socket;
    try {
      socket = await this.c.tcp(e, address);
    } catch (err) {
      return this.c.failed('tcp', err, (p) => this.tcpFailure(e, where, p));
    }
    this.c.pass('tcp', `${where} accepts TCP connections`);
    try {
      const tried = addressingOf(e);
      const answer = await this.connectionRequest(socket, tried, e);
      if (answer.kind !== 'accepted') await this.cotpFailure(e, address, tried, answer);
      this.c.pass(
        'cotp',
        `the CPU accepted the connection request (${tried.label}: called TSAP 0x${hex4(tried.calledTsap)}, calling TSAP 0x${hex4(tried.callingTsap)})`,
      );
      await this.setup(socket, e);
    } finally {
      socket.destroy();
    }
  }

  private tcpFailure(e: S7Endpoint, where: string, p: PlcError): never {
    const code = (p.cause as NodeJS.ErrnoException | undefined)?.code;
    if (p.code === 'TIMEOUT') {
      this.c.fail(
        'tcp',
        `no answer from ${where} within ${this.c.stepTimeout(e)} ms: filtered (the connection attempt got no reply at all)`,
        HINT.filtered(e.port),
      );
    }
    if (code === 'ECONNREFUSED') {
      this.c.fail(
        'tcp',
        `${where} refused the connection (ECONNREFUSED): the host is up, but nothing listens on port ${e.port}`,
        HINT.refused,
      );
    }
    if (code === 'EHOSTUNREACH' || code === 'ENETUNREACH') {
      this.c.fail('tcp', `no route to ${where} (${code})`, HINT.noRoute);
    }
    this.c.fail('tcp', p.message);
  }

  /** Sends a COTP connection request and waits for the answer frame. */
  private async connectionRequest(socket: net.Socket, a: Addressing, e: S7Endpoint): Promise<CotpAnswer> {
    const frames = new FrameWaiter(socket, this.c.signal);
    try {
      socket.write(
        encodeConnectionRequest({ sourceRef: 0x0001, callingTsap: a.callingTsap, calledTsap: a.calledTsap, tpduSize: TPDU_SIZE_CODE }),
      );
      const frame = await frames.next(this.c.stepTimeout(e));
      if (frame.kind !== 'frame') return frame;
      const m = decodeCotp(frame.frame);
      if (m.type === 'CC') return { kind: 'accepted' };
      if (m.type === 'DR') return { kind: 'refused', reason: m.reason };
      return { kind: 'foreign', message: `a COTP ${m.type} instead of a connection confirm` };
    } catch (err) {
      if (this.c.signal.aborted) throw err;
      return { kind: 'foreign', message: (err as Error).message };
    } finally {
      frames.stop();
    }
  }

  private async cotpFailure(
    e: S7Endpoint,
    address: string,
    tried: Addressing,
    answer: Exclude<CotpAnswer, { kind: 'accepted' }>,
  ): Promise<never> {
    const asked = (why: string) =>
      `${tried.label} (called TSAP 0x${hex4(tried.calledTsap)}, calling TSAP 0x${hex4(tried.callingTsap)}; ${why})`;
    if (answer.kind === 'silent') {
      this.c.fail(
        'cotp',
        `port ${e.port} accepts TCP but nothing answered the ISO-on-TCP connection request within ${answer.ms} ms`,
        HINT.notIsoOnTcp,
      );
    }
    if (answer.kind === 'foreign') {
      this.c.fail('cotp', `the answer is not an ISO-on-TCP connection confirm: ${answer.message}`, HINT.otherProtocol);
    }
    if (answer.kind === 'refused' && answer.reason === DR_CONGESTION) {
      this.c.fail(
        'cotp',
        `the CPU refused the connection request for ${asked('COTP disconnect, reason 1: congestion')}: no free connection`,
        HINT.congestion,
      );
    }
    const how = answer.kind === 'refused' ? `COTP disconnect, reason ${answer.reason}` : 'it closed the connection without an answer';
    const found = await this.findAddressing(e, address);
    this.c.fail('cotp', `the CPU refused the connection request for ${asked(how)}: wrong rack/slot or TSAP`, HINT.addressing(found));
  }

  /** Tries the usual addressings, one connection each (closed at once), until one is accepted. */
  private async findAddressing(e: S7Endpoint, address: string): Promise<Addressing | undefined> {
    for (const a of alternatives(e)) {
      if (this.c.signal.aborted) return undefined;
      let socket: net.Socket | undefined;
      try {
        socket = await this.c.tcp(e, address);
        if ((await this.connectionRequest(socket, a, e)).kind === 'accepted') return a;
      } catch {
        if (this.c.signal.aborted) return undefined;
      } finally {
        socket?.destroy();
      }
    }
    return undefined;
  }

  private async setup(socket: net.Socket, e: S7Endpoint): Promise<void> {
    const frames = new FrameWaiter(socket, this.c.signal);
    try {
      socket.write(encodeSetupCommunication(0, { maxAmqCalling: REQUESTED_AMQ, maxAmqCalled: REQUESTED_AMQ, pduSize: e.pduSize }));
      const answer = await frames.next(this.c.stepTimeout(e));
      if (answer.kind === 'silent') this.c.fail('setup', `no answer to setup communication within ${answer.ms} ms`, HINT.setupSilent);
      if (answer.kind === 'closed') this.c.fail('setup', 'the CPU closed the connection at setup communication', HINT.setupClosed);
      if (answer.kind === 'foreign') this.c.fail('setup', `the answer to setup communication is malformed: ${answer.message}`);
      const ack = decodeS7(answer.frame);
      if (ack.kind === 'error') {
        const err = headerError(ack.errorClass, ack.errorCode, 'setup communication');
        this.c.fail('setup', err.message, HINT.setupRefused);
      }
      if (ack.kind !== 'setup-ack') this.c.fail('setup', `the answer to setup communication is a ${ack.kind}`);
      const { pduSize, maxAmqCalling, maxAmqCalled } = ack.params;
      if (pduSize < 64) this.c.fail('setup', `the CPU negotiated an unusable PDU size of ${pduSize} bytes`);
      const amq = Math.max(1, Math.min(maxAmqCalling, maxAmqCalled, REQUESTED_AMQ));
      this.c.pass('setup', `PDU ${pduSize} bytes (asked ${e.pduSize}), ${amq} parallel job${amq === 1 ? '' : 's'} (AmQ)`);
    } catch (err) {
      return this.c.failed('setup', err, (p) => this.c.fail('setup', p.message));
    } finally {
      frames.stop();
    }
  }
}

type CotpAnswer =
  | { kind: 'accepted' }
  | { kind: 'refused'; reason: number }
  | { kind: 'closed' }
  | { kind: 'silent'; ms: number }
  | { kind: 'foreign'; message: string };
type FrameResult =
  { kind: 'frame'; frame: Buffer } | { kind: 'closed' } | { kind: 'silent'; ms: number } | { kind: 'foreign'; message: string };

/** Whole TPKT frames from a raw socket, one at a time, each with its own wait. */
class FrameWaiter {
  private readonly reader = new FrameReader(checkTpkt, MAX_FRAME);
  private readonly frames: Buffer[] = [];
  private end: FrameResult | undefined;
  private wake: (() => void) | undefined;
  private readonly onData = (chunk: Buffer) => {
    try {
      this.frames.push(...this.reader.push(chunk));
    } catch (err) {
      this.end ??= { kind: 'foreign', message: (err as Error).message };
    }
    this.wake?.();
  };
  private readonly onClose = () => {
    this.end ??= { kind: 'closed' };
    this.wake?.();
  };

  constructor(
    private readonly socket: net.Socket,
    private readonly signal: AbortSignal,
  ) {
    socket.on('data', this.onData);
    socket.on('close', this.onClose);
    if (socket.destroyed) this.end = { kind: 'closed' };
  }

  next(ms: number): Promise<FrameResult> {
    return new Promise((resolve, reject) => {
      const done = () => {
        clearTimeout(timer);
        this.wake = undefined;
        this.signal.removeEventListener('abort', onAbort);
      };
      const check = () => {
        const frame = this.frames.shift();
        if (frame) return (done(), resolve({ kind: 'frame', frame }), true);
        if (this.end) return (done(), resolve(this.end), true);
        return false;
      };
      const onAbort = () => (done(), reject(abortError('waiting for a frame', this.signal)));
      const timer = setTimeout(() => (done(), resolve({ kind: 'silent', ms })), ms);
      if (check()) return;
      if (this.signal.aborted) return onAbort();
      this.signal.addEventListener('abort', onAbort, { once: true });
      this.wake = () => void check();
    });
  }

  stop(): void {
    this.socket.removeListener('data', this.onData);
    this.socket.removeListener('close', this.onClose);
  }
}
