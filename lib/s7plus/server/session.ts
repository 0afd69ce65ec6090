/**
 * One S7CommPlus session as a CPU keeps it: InitSSL, CreateObject (the
 * session id and ServerSessionVersion), the setup write that echoes it, then
 * data requests whose integrity ids (one counter for reads, one for writes)
 * must follow on without a gap: a jump resets the connection, as a PLC does.
 * Takes whole S7CommPlus frames, gives whole frames; the transport
 * (connection.ts) carries them. Layouts: s7commplus (MIT) connection.py
 * (`_send_request`: where the integrity id sits), server.py.
 */
import { ProtocolError } from '../../errors';
import {
  DataType,
  ElementId,
  FunctionCode,
  Ids,
  ITEM_ERROR_UNRESOLVED,
  Opcode,
  ProtocolVersion,
  PValueFlag,
  READ_FUNCTIONS,
  S7P_PROTOCOL_ID,
} from '../constants';
import { Reader } from '../codec/bytes';
import { encodeUVlq32, encodeUVlq64 } from '../codec/vlq';
import { FULL_ACCESS, Legitimation } from './legitimation';
import { decodeObject } from '../codec/object';
import { readAlarmSubscription } from '../codec/alarms';
import { AlarmSubscriptions } from './alarm-subscriptions';
import { AlarmSubsystem } from './alarms';
import { Subscriptions } from './subscriptions';
import { explore, getMultiVariables, getVarSubStreamed, ResetConnection, setMultiVariables, type CpuSide } from './services';

/** The device string of ServerSessionVersion by default: an S7-1500 at firmware V3.1 (the form of legitimation.py's examples). */
const DEFAULT_DEVICE = '1;6ES7 516-3AN02-0AB0 ;V3.1';
/** A refused legitimation's return value: bit 15 set (connection.py _check_set_variable_response). */
const LEGITIMATION_REFUSED = 0x8000n;

export interface SessionOptions {
  readonly tls: boolean;
  /** Bytes of a request frame the CPU takes; a longer one resets the connection. */
  readonly maxRequestBytes: number;
  newSessionId(): number;
  /** Sends a frame the client did not ask for (a notification). */
  push(frame: Buffer): void;
  /** The CPU's password (`--password-file`): without it the session has read access only. */
  readonly password?: string | undefined;
  /** The TLS exporter secret the legitimation key derives from; undefined without TLS. */
  exporter(): Buffer | undefined;
  /** The device string of ServerSessionVersion (`1;<order number>;V<firmware>`): its firmware decides the legitimation's form. */
  readonly device?: string | undefined;
}

/** What the transport does after a frame: send `reply`; switch to TLS; close. */
export interface Step {
  readonly reply?: Buffer;
  readonly startTls?: boolean;
  readonly close?: boolean;
}

export class PlusSession {
  private stage: 'init' | 'ssl' | 'created' | 'ready' = 'init';
  private sessionId = 0;
  private readId = 0;
  private writeId = 0;
  /** The session's subscription container: the second object id of its CreateObject. */
  private container = 0;
  private readonly subscriptions: Subscriptions;
  private readonly alarmSubscriptions: AlarmSubscriptions;
  private readonly legitimation: Legitimation;

  constructor(
    private readonly cpu: CpuSide,
    private readonly options: SessionOptions,
  ) {
    this.subscriptions = new Subscriptions(cpu, options.push, this.version());
    // A CPU without alarms defined still has its alarm subsystem: a subscription to it is taken and stays quiet.
    this.alarmSubscriptions = new AlarmSubscriptions(cpu.alarms ?? new AlarmSubsystem([], () => cpu.model), options.push, this.version());
    this.legitimation = new Legitimation(options.password, options.exporter, options.device ?? DEFAULT_DEVICE);
  }

  /** The connection ended: no more notifications. */
  close(): void {
    this.subscriptions.clear();
    this.alarmSubscriptions.clear();
  }

  /** Handles one frame (header, data, trailer); throws ProtocolError for a frame that breaks the protocol (the connection is then reset). */
  handle(frame: Buffer): Step {
    if (frame.length > this.options.maxRequestBytes) {
      throw new ResetConnection(`a request of ${frame.length} bytes, more than the ${this.options.maxRequestBytes} the CPU takes`);
    }
    if (frame.length < 8 + 14 || frame[0] !== S7P_PROTOCOL_ID) throw new ProtocolError('not an S7CommPlus request frame');
    const length = frame.readUInt16BE(2);
    if (4 + length > frame.length) throw new ProtocolError(`S7CommPlus frame says ${length} bytes of data, carries ${frame.length - 4}`);
    const data = frame.subarray(4, 4 + length);
    if (data[0] !== Opcode.Request) throw new ProtocolError(`S7CommPlus opcode 0x${data[0]!.toString(16)} where a request was expected`);
    const fn = data.readUInt16BE(3);
    const seq = data.readUInt16BE(7);
    const session = data.readUInt32BE(9);
    const transport = data[13]!;
    const body = data.subarray(14);
    if (this.stage !== 'init' && this.stage !== 'ssl' && fn !== FunctionCode.CreateObject && session !== this.sessionId) {
      throw new ResetConnection(`request for session ${session}, this connection's is ${this.sessionId}`);
    }
    switch (this.stage) {
      case 'init':
        if (fn !== FunctionCode.InitSsl) throw new ProtocolError(`S7CommPlus function 0x${fn.toString(16)} before InitSSL`);
        this.stage = 'ssl';
        return {
          reply: this.frame(ProtocolVersion.V1, fn, seq, Buffer.concat([encodeUVlq32(0), Buffer.alloc(4)])),
          startTls: this.options.tls,
        };
      case 'ssl':
        if (fn !== FunctionCode.CreateObject) throw new ProtocolError(`S7CommPlus function 0x${fn.toString(16)} before CreateObject`);
        this.sessionId = this.options.newSessionId();
        this.container = this.options.newSessionId();
        this.stage = 'created';
        return { reply: this.frame(ProtocolVersion.V1, fn, seq, this.created()) };
      case 'created':
        if (fn !== FunctionCode.SetMultiVariables)
          throw new ProtocolError(`S7CommPlus function 0x${fn.toString(16)} before the session setup`);
        this.stage = 'ready';
        return { reply: this.frame(this.version(), fn, seq, Buffer.concat([encodeUVlq64(0n), encodeUVlq32(0)])) };
      default:
        return this.data(fn, seq, body, transport);
    }
  }

  private version(): number {
    return this.options.tls ? ProtocolVersion.V2 : ProtocolVersion.V1;
  }

  private data(fn: number, seq: number, body: Buffer, transport: number): Step {
    if (fn === FunctionCode.DeleteObject && body.length <= 4) {
      this.stage = 'init';
      this.subscriptions.clear();
      this.alarmSubscriptions.clear();
      return { reply: this.frame(this.version(), fn, seq, Buffer.concat([encodeUVlq64(0n), Buffer.alloc(4)])), close: true };
    }
    const read = READ_FUNCTIONS.has(fn);
    const id = this.options.tls ? this.checkIntegrity(fn, body, read ? this.readId : this.writeId) : undefined;
    let answer: Buffer;
    switch (fn) {
      case FunctionCode.CreateObject:
        answer = this.createSubscription(body, id);
        break;
      case FunctionCode.DeleteObject:
        answer = this.deleteObject(body);
        break;
      case FunctionCode.SetVariable:
        answer = Buffer.concat([encodeUVlq64(this.setVariable(body)), Buffer.alloc(4)]);
        // The credit update comes with transport flags 0x74: no answer (connection.py send_subscription_credit).
        if (transport & 0x40) {
          if (id !== undefined) this.writeId = (this.writeId + 1) >>> 0;
          return {};
        }
        break;
      case FunctionCode.Explore:
        answer = explore(this.cpu, body);
        break;
      case FunctionCode.GetMultiVariables:
        answer = getMultiVariables(this.cpu, body);
        break;
      case FunctionCode.SetMultiVariables:
        answer = setMultiVariables(this.cpu, body, this.legitimation.level === FULL_ACCESS);
        break;
      case FunctionCode.GetVarSubStreamed:
        answer = this.subStreamed(body);
        break;
      default:
        // Any other function: the CPU's error answer (server.py _build_error_response).
        return { reply: this.frame(this.version(), FunctionCode.Error, seq, Buffer.concat([encodeUVlq32(0x04b1), Buffer.alloc(4)])) };
    }
    if (id !== undefined) {
      if (read) this.readId = (this.readId + 1) >>> 0;
      else this.writeId = (this.writeId + 1) >>> 0;
      answer = Buffer.concat([answer, encodeUVlq32(id)]);
    }
    return { reply: this.frame(this.version(), fn, seq, answer) };
  }

  /**
   * The request's integrity id must be the next of its counter: it sits
   * just before the request's fixed tail (5 bytes for Explore, 4 otherwise;
   * connection.py `_send_request`). Anything else is a jump: reset.
   */
  private checkIntegrity(fn: number, body: Buffer, expected: number): number {
    const id = encodeUVlq32(expected);
    // A CreateObject carries it after its request set (container id, value, fill: 11 bytes; subscription.py).
    if (fn === FunctionCode.CreateObject) {
      if (body.subarray(11, 11 + id.length).equals(id)) return expected;
      throw new ResetConnection(`integrity id of a CreateObject is not the expected ${expected}: the counters jumped`);
    }
    // A DeleteObject of plcwire's form (codec/session.ts): the object id as four fixed bytes, the id, a fill of 4; its
    // last byte is no VLQ, so the rule below would misread an object id ending in a byte with bit 7 set (0x3A0).
    if (fn === FunctionCode.DeleteObject && body.length === 8 + id.length && body.subarray(4, 4 + id.length).equals(id)) return expected;
    const tails = fn === FunctionCode.Explore ? [5] : [4, 3];
    for (const tail of tails) {
      const at = body.length - tail - id.length;
      if (at >= 0 && body.subarray(at, at + id.length).equals(id)) {
        // The byte before must end a field, not continue a VLQ.
        if (at === 0 || (body[at - 1]! & 0x80) === 0) return expected;
      }
    }
    throw new ResetConnection(`integrity id of function 0x${fn.toString(16)} is not the expected ${expected}: the counters jumped`);
  }

  private subStreamed(body: Buffer): Buffer {
    const r = new Reader(body);
    r.u32('the object id');
    r.bytes(3, 'the address array head');
    const address = r.uvlq32();
    if (address === Ids.EffectiveProtectionLevel) return getVarSubStreamed(this.legitimation.level);
    if (address === Ids.ServerSessionRequest) {
      // The legitimation challenge, as a USInt array (connection.py _parse_get_var_substreamed_response).
      const challenge = this.legitimation.newChallenge();
      return Buffer.concat([
        encodeUVlq64(0n),
        Buffer.from([0x00, 0x10, DataType.USInt]),
        encodeUVlq32(challenge.length),
        challenge,
        Buffer.alloc(4),
      ]);
    }
    // Any other address: an error return value (the item error the simulator uses, server.py _ITEM_ERROR).
    return Buffer.concat([encodeUVlq64(ITEM_ERROR_UNRESOLVED), Buffer.alloc(4)]);
  }

  /** A subscription (of variables, or of alarms: one with an AlarmSubscriptionRef child) under the session's container: its object id. */
  private createSubscription(body: Buffer, id: number | undefined): Buffer {
    const r = new Reader(body);
    if (r.u32('the container id') !== this.container)
      throw new ProtocolError("S7CommPlus CreateObject outside the session's subscription container");
    const object = body.subarray(11 + (id === undefined ? 0 : encodeUVlq32(id).length));
    const alarms = object[0] === ElementId.StartOfObject ? readAlarmSubscription(decodeObject(object).value) : undefined;
    const created = alarms ? this.alarmSubscriptions.create(alarms) : this.subscriptions.create(object);
    return Buffer.concat([encodeUVlq64(0n), Buffer.from([1]), encodeUVlq32(created), Buffer.alloc(4)]);
  }

  /** DeleteObject of the subscription container: every subscription ends. */
  private deleteObject(body: Buffer): Buffer {
    const object = new Reader(body).u32('the object id');
    if (object !== this.container) return Buffer.concat([encodeUVlq64(ITEM_ERROR_UNRESOLVED), Buffer.alloc(4)]);
    this.subscriptions.clear();
    this.alarmSubscriptions.clear();
    return Buffer.concat([encodeUVlq64(0n), Buffer.alloc(4)]);
  }

  /** SetVariable: a subscription's credit limit, or the session's legitimation; the return value (an error has bit 15 set). */
  private setVariable(body: Buffer): bigint {
    const r = new Reader(body);
    const object = r.u32('the object id');
    if (r.uvlq32() !== 1) return LEGITIMATION_REFUSED;
    const address = r.uvlq32();
    const flags = r.u8('flags');
    const type = r.u8('type');
    if (address === Ids.SubscriptionCreditLimit && type === DataType.Int) {
      const limit = r.bytes(2, 'an Int').readInt16BE(0);
      if (this.alarmSubscriptions.has(object)) this.alarmSubscriptions.setCredit(object, limit);
      else this.subscriptions.setCredit(object, limit);
    } else if (address === Ids.Legitimate && type === DataType.Blob) {
      r.uvlq32();
      return this.legitimation.attempt(r.bytes(r.uvlq32(), 'the credentials')) ? 0n : LEGITIMATION_REFUSED;
    } else if (address === Ids.ServerSessionResponse && type === DataType.USInt && flags & PValueFlag.Array) {
      // The legacy form's answer, a USInt array (connection.py _send_legitimation_legacy).
      return this.legitimation.attemptLegacy(r.bytes(r.uvlq32(), 'the legacy answer')) ? 0n : LEGITIMATION_REFUSED;
    }
    return 0n;
  }

  /** The CreateObject answer: the session id and its subscription container, then the session object with its ServerSessionVersion. */
  private created(): Buffer {
    const rel = Buffer.alloc(4);
    rel.writeUInt32BE(1);
    return Buffer.concat([
      encodeUVlq64(0n),
      Buffer.from([2]),
      encodeUVlq32(this.sessionId),
      encodeUVlq32(this.container),
      Buffer.from([ElementId.StartOfObject]),
      rel,
      encodeUVlq32(0),
      encodeUVlq32(0),
      encodeUVlq32(0),
      Buffer.from([ElementId.Attribute]),
      encodeUVlq32(Ids.ServerSessionVersion),
      this.sessionVersion(),
      Buffer.from([ElementId.TerminatingObject]),
      Buffer.alloc(4),
    ]);
  }

  /**
   * ServerSessionVersion: Struct 314 with the protocol version (315) and the
   * device string (319) whose firmware tells a client which legitimation the
   * CPU takes: V3.1 of an S7-1500, the "new" one (legitimation.py).
   */
  private sessionVersion(): Buffer {
    const id = Buffer.alloc(4);
    id.writeUInt32BE(Ids.SessionVersionStruct);
    const paom = Buffer.from(this.options.device ?? DEFAULT_DEVICE, 'utf8');
    return Buffer.concat([
      Buffer.from([0x00, DataType.Struct]),
      id,
      encodeUVlq32(315),
      Buffer.from([0x00, DataType.UDInt]),
      encodeUVlq32(this.version()),
      encodeUVlq32(Ids.SessionVersionSystemPaomString),
      Buffer.from([0x00, DataType.WString]),
      encodeUVlq32(paom.length),
      paom,
      Buffer.from([0x00]),
    ]);
  }

  /** A response frame: header, the 10-byte response header, the body, the trailer. */
  private frame(version: number, fn: number, seq: number, body: Buffer): Buffer {
    const head = Buffer.alloc(14);
    head[0] = S7P_PROTOCOL_ID;
    head[1] = version;
    // connection.ts cuts a long response into frames of its own and writes their lengths; this one is not read then.
    head.writeUInt16BE(Math.min(10 + body.length, 0xffff), 2);
    head[4] = Opcode.Response;
    head.writeUInt16BE(fn, 7);
    head.writeUInt16BE(seq, 11);
    const trailer = Buffer.from([S7P_PROTOCOL_ID, version, 0, 0]);
    return Buffer.concat([head, body, trailer]);
  }
}
