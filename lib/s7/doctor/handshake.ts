/**
 * The connection doctor's handshake steps (lib/s7/doctor/index.ts): TCP, the
 * COTP connection request and setup communication, run with the client's own
 * step functions (openTcp, the ISO connect step of lib/iso/connect.ts,
 * `exchangeSetup` of client/handshake.ts), each with the URL's timeout. What
 * only the doctor does is here: each answer told apart in its words (a COTP
 * disconnect and its reason, silence, a foreign protocol), and after a
 * refused connection request the usual addressings, to say which one the
 * CPU accepts.
 */
import type * as net from 'node:net';
import type { PlcError } from '../../errors';
import { IsoConnectError, requestIsoConnection, type IsoRefusal } from '../../iso/connect';
import { DR_CONGESTION } from '../../iso/constants';
import { IsoFrames } from '../../iso/frames';
import type { S7Endpoint } from '../url';
import { exchangeSetup } from '../client/handshake';
import { TPDU_SIZE_CODE, headerError } from '../constants';
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
    const frames = new IsoFrames(socket, this.c.signal, 'the connection doctor');
    try {
      const tried = addressingOf(e);
      const refusal = await this.connectionRequest(socket, frames, tried, e, where);
      if (refusal) await this.cotpFailure(e, address, tried, refusal);
      this.c.pass(
        'cotp',
        `the CPU accepted the connection request (${tried.label}: called TSAP 0x${hex4(tried.calledTsap)}, calling TSAP 0x${hex4(tried.callingTsap)})`,
      );
      await this.setup(socket, frames, e);
    } finally {
      frames.stop();
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

  /** The ISO connect step's CR → CC with addressing `a`: undefined when the CPU confirms, else what it did instead. */
  private async connectionRequest(
    socket: net.Socket,
    frames: IsoFrames,
    a: Addressing,
    e: S7Endpoint,
    where: string,
  ): Promise<IsoRefusal | undefined> {
    try {
      await requestIsoConnection(socket, frames, {
        name: where,
        callingTsap: a.callingTsap,
        calledTsap: a.calledTsap,
        tpduSize: TPDU_SIZE_CODE,
        answerTimeout: this.c.stepTimeout(e),
        signal: this.c.signal,
      });
      return undefined;
    } catch (err) {
      if (this.c.signal.aborted) throw err;
      if (err instanceof IsoConnectError) return err.refusal;
      return { kind: 'garbage', message: (err as Error).message };
    }
  }

  private async cotpFailure(e: S7Endpoint, address: string, tried: Addressing, refusal: IsoRefusal): Promise<never> {
    const asked = (why: string) =>
      `${tried.label} (called TSAP 0x${hex4(tried.calledTsap)}, calling TSAP 0x${hex4(tried.callingTsap)}; ${why})`;
    const notIso = (what: string) => this.c.fail('cotp', `the answer is not an ISO-on-TCP connection confirm: ${what}`, HINT.otherProtocol);
    switch (refusal.kind) {
      case 'silent':
        return this.c.fail(
          'cotp',
          `port ${e.port} accepts TCP but nothing answered the ISO-on-TCP connection request within ${refusal.ms} ms`,
          HINT.notIsoOnTcp,
        );
      case 'garbage':
        return notIso(refusal.message);
      case 'error':
        return notIso('a COTP ER instead of a connection confirm');
      case 'unexpected':
        return notIso(`a COTP ${refusal.type} instead of a connection confirm`);
      case 'disconnect':
        if (refusal.reason === DR_CONGESTION) {
          this.c.fail(
            'cotp',
            `the CPU refused the connection request for ${asked('COTP disconnect, reason 1: congestion')}: no free connection`,
            HINT.congestion,
          );
        }
        break;
      case 'closed':
        break;
    }
    const how = refusal.kind === 'disconnect' ? `COTP disconnect, reason ${refusal.reason}` : 'it closed the connection without an answer';
    const found = await this.findAddressing(e, address);
    this.c.fail('cotp', `the CPU refused the connection request for ${asked(how)}: wrong rack/slot or TSAP`, HINT.addressing(found));
  }

  /** Tries the usual addressings, one connection each (closed at once), until one is accepted. */
  private async findAddressing(e: S7Endpoint, address: string): Promise<Addressing | undefined> {
    for (const a of alternatives(e)) {
      if (this.c.signal.aborted) return undefined;
      let socket: net.Socket | undefined;
      let frames: IsoFrames | undefined;
      try {
        socket = await this.c.tcp(e, address);
        frames = new IsoFrames(socket, this.c.signal, 'the connection doctor');
        if ((await this.connectionRequest(socket, frames, a, e, `${address}:${e.port}`)) === undefined) return a;
      } catch {
        if (this.c.signal.aborted) return undefined;
      } finally {
        frames?.stop();
        socket?.destroy();
      }
    }
    return undefined;
  }

  /** The client's setup step (exchangeSetup), each answer in the doctor's words. */
  private async setup(socket: net.Socket, frames: IsoFrames, e: S7Endpoint): Promise<void> {
    try {
      const answer = await exchangeSetup(socket, frames, e.pduSize, this.c.stepTimeout(e));
      switch (answer.kind) {
        case 'silent':
          return this.c.fail('setup', `no answer to setup communication within ${answer.ms} ms`, HINT.setupSilent);
        case 'closed':
          return this.c.fail('setup', 'the CPU closed the connection at setup communication', HINT.setupClosed);
        case 'garbage':
          return this.c.fail('setup', `the answer to setup communication is malformed: ${answer.error.message}`);
        case 'refused':
          return this.c.fail('setup', headerError(answer.errorClass, answer.errorCode, 'setup communication').message, HINT.setupRefused);
        case 'other':
          return this.c.fail('setup', `the answer to setup communication is a ${answer.what}`);
        case 'unusable':
          return this.c.fail('setup', `the CPU negotiated an unusable PDU size of ${answer.pduSize} bytes`);
        case 'granted': {
          const amq = answer.maxJobs;
          this.c.pass('setup', `PDU ${answer.pduSize} bytes (asked ${e.pduSize}), ${amq} parallel job${amq === 1 ? '' : 's'} (AmQ)`);
        }
      }
    } catch (err) {
      return this.c.failed('setup', err, (p) => this.c.fail('setup', p.message));
    }
  }
}
