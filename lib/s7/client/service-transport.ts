/**
 * How the S7 system services (services.ts) talk to the CPU: a userdata
 * request and its answer checked against the service asked for, the further
 * parts of a multi-part answer, control jobs, and what a malformed answer
 * does to the link. One job on the session each, like a Read Var.
 */
import { PlcError, ProtocolError } from '../../errors';
import type { S7Endpoint } from '../url';
import { decodeControl, type ControlMessage } from '../codec/control';
import { decodeUserdata, encodeUserdataNext, encodeUserdataRequest, type UserdataPdu } from '../codec/userdata';
import {
  BlockSubfunction,
  CpuSubfunction,
  SecuritySubfunction,
  TimeSubfunction,
  UserdataGroup,
  UserdataType,
  serviceError,
} from '../constants';
import { linkError, type S7Session } from './session';

/** What the services need from S7Client: its name, its endpoint, and its live session, whose exchange they talk to. */
export interface ServiceHost {
  readonly name: string;
  readonly endpoint: S7Endpoint;
  /** The live session; throws NOT_CONNECTED when there is none. */
  session(): S7Session;
  /** The live session, if any. */
  current(): S7Session | undefined;
}

/** A multi-part answer longer than this many parts is not a CPU's. */
const MAX_PARTS = 4096;

/** A userdata service: its function group and subfunction, which its answer repeats. */
export interface Service {
  readonly group: UserdataGroup;
  readonly subfunction: number;
}

/** The userdata services asked for here, named after their subfunctions. */
export const SERVICE = Object.freeze({
  readSzl: { group: UserdataGroup.Cpu, subfunction: CpuSubfunction.ReadSzl },
  readClock: { group: UserdataGroup.Time, subfunction: TimeSubfunction.ReadClock },
  setClock: { group: UserdataGroup.Time, subfunction: TimeSubfunction.SetClock },
  listAll: { group: UserdataGroup.Block, subfunction: BlockSubfunction.ListAll },
  listType: { group: UserdataGroup.Block, subfunction: BlockSubfunction.ListType },
  blockInfo: { group: UserdataGroup.Block, subfunction: BlockSubfunction.BlockInfo },
  setPassword: { group: UserdataGroup.Security, subfunction: SecuritySubfunction.SetPassword },
  clearPassword: { group: UserdataGroup.Security, subfunction: SecuritySubfunction.ClearPassword },
} satisfies Record<string, Service>);

/** The transport of the services: S7Services builds on it. */
export abstract class ServiceTransport {
  constructor(protected readonly host: ServiceHost) {}

  // ---------------------------------------------------------------- transport

  /** A malformed answer: the live link drops (as for any frame the client cannot make sense of); the error to throw. */
  protected malformed(err: unknown): PlcError {
    return this.host.current()?.malformed(err) ?? linkError(this.host.name, err);
  }

  /** Asks for a userdata service: one request, its answer checked (the first part of a multi-part one). */
  protected request(service: Service, what: string, signal?: AbortSignal, data?: Buffer): Promise<UserdataPdu> {
    return this.userdata(encodeUserdataRequest(service.group, service.subfunction, data), service, what, signal);
  }

  protected async userdata(frame: Buffer, { group, subfunction }: Service, what: string, signal?: AbortSignal): Promise<UserdataPdu> {
    const answer = await this.host.session().exchange(frame, what, signal);
    let u: UserdataPdu;
    try {
      u = decodeUserdata(answer);
      const p = u.params;
      if (p.type !== UserdataType.Response || p.group !== group || p.subfunction !== subfunction) {
        throw new ProtocolError(`the answer to ${what} is a userdata of type ${p.type}, group ${p.group}, subfunction ${p.subfunction}`);
      }
      if (p.errorCode === undefined) throw new ProtocolError(`the answer to ${what} has no error field (8-byte parameters)`);
    } catch (err) {
      throw this.malformed(err);
    }
    if (u.params.errorCode) throw serviceError(u.params.errorCode, `${this.host.name} ${what}`);
    return u;
  }

  /** Every part of an answer: the first, then the next ones asked for with the CPU's sequence number and data unit reference. */
  protected async allParts(first: UserdataPdu, service: Service, what: string, signal?: AbortSignal): Promise<Buffer> {
    const parts = [first.data];
    let u = first;
    while (u.params.lastDataUnit === false) {
      if (parts.length >= MAX_PARTS) throw this.malformed(new ProtocolError(`${what}: more than ${MAX_PARTS} parts`));
      const next = encodeUserdataNext(service.group, service.subfunction, u.params.sequence, u.params.dataUnitRef ?? 0);
      u = await this.userdata(next, service, `${what} (part ${parts.length + 1})`, signal);
      parts.push(u.data);
    }
    return Buffer.concat(parts);
  }

  protected async control(frame: Buffer, what: string, signal?: AbortSignal): Promise<ControlMessage> {
    const answer = await this.host.session().exchange(frame, what, signal);
    try {
      return decodeControl(answer);
    } catch (err) {
      throw this.malformed(err);
    }
  }

  protected controlRefusal(what: string): PlcError | undefined {
    const e = this.host.endpoint;
    if (e.readOnly) return new PlcError('WRITE_NOT_ALLOWED', `${what} refused: the connection is read-only`);
    if (!e.control)
      return new PlcError('WRITE_NOT_ALLOWED', `${what} refused: the connection does not allow PLC control (add control=true to the URL)`);
    return undefined;
  }
}
