/**
 * The simulated CPU's cyclic data (userdata group 2; codec/cyclic.ts): an
 * S7-300/400 registers a connection's jobs, answers each with its job id and
 * the first values, then pushes the job's items every n × time base (a
 * change-driven job only when a value changed since its last push) until
 * the job is unsubscribed or the connection closes. The values are read as a
 * Read Var of the same items reads them (jobs.ts serveRead), return codes
 * per item included. Other CPUs refuse the group as they refuse any service
 * they lack (0x8104).
 *
 * Limits: a CPU 315-2 PN/DP (the s7-300 profile) reports 16 cyclic jobs of
 * 100 ms to 52.1 s in SZL 0x0131 index 3 (profiles.ts), and the simulator
 * holds to them; an S7-400 profile, whose record was not found, gets 16 jobs
 * of 100 ms to 25.5 s (255 × 100 ms … 255 × 10 s are codable): the
 * simulator's choice. Beyond the jobs: 0xD805 "no more cyclic read jobs can
 * be set up"; a period outside: 0xD804 "illegal cycle time" (Wireshark's
 * s7comm error table).
 */
import type * as net from 'node:net';
import {
  CYCLIC_ERRORS,
  CYCLIC_TIME_BASE_MS,
  CyclicSubfunction,
  decodeCyclicSubscribe,
  decodeCyclicUnsubscribe,
  encodeCyclicAnswer,
  encodeCyclicPush,
  encodeCyclicValues,
  UNSUBSCRIBE_ONE_JOB,
  type CyclicJob,
} from '../codec/cyclic';
import { encodeReadRequest, type ReadResponseItem } from '../codec/pdu';
import { decodeS7 } from '../codec/pdu-decode';
import { decodeUserdata, encodeUserdataResponse } from '../codec/userdata';
import { UserdataGroup } from '../constants';
import { serveRead, type JobContext } from './jobs';
import type { CpuIdentity } from './profiles';
import { SERVICE_CODE } from './service-codes';

export { isCyclicRequest } from '../codec/cyclic';

/** Bytes a cyclic request and push take beyond the Read Var job and ack of the same items (userdata parameters and item head). */
const CYCLIC_EXTRA = 14;
/** The S7-400 fallback (see above). */
const S7_400_LIMITS: CyclicLimits = Object.freeze({ maxJobs: 16, minPeriodMs: 100, maxPeriodMs: 25_500 });

/** How many cyclic jobs a CPU runs at once and the periods it accepts. */
export interface CyclicLimits {
  maxJobs: number;
  minPeriodMs: number;
  maxPeriodMs: number;
}

/** The CPU's limits (undefined: it has no cyclic services): S7-300/400 order codes only (6ES7 3…, 6ES7 4…). */
function cyclicLimits(identity: Readonly<CpuIdentity>): CyclicLimits | undefined {
  const record = identity.communicationRecords?.[3];
  if (record) {
    const r = Buffer.from(record, 'hex');
    // index 0-1, funkt_0..3 2-5, data 6-7, anz 8-9, per_min 10-11, per_max 12-13 (n × 100 ms).
    return { maxJobs: r.readUInt16BE(8), minPeriodMs: r.readUInt16BE(10) * 100, maxPeriodMs: r.readUInt16BE(12) * 100 };
  }
  return /^6ES7 4/.test(identity.orderCode) ? S7_400_LIMITS : undefined;
}

interface Running {
  job: CyclicJob;
  timer: NodeJS.Timeout;
  last: Buffer | undefined;
}

/** The cyclic jobs of one simulated CPU, over all its connections. */
export class CyclicService {
  private readonly limits: CyclicLimits | undefined;
  private readonly byConnection = new Map<net.Socket, Map<number, Running>>();
  private running = 0;

  constructor(identity: Readonly<CpuIdentity>) {
    this.limits = cyclicLimits(identity);
  }

  /** Jobs running now, on every connection. */
  get jobCount(): number {
    return this.running;
  }

  /** Answers a userdata request of group 2 from `socket`; throws ProtocolError on a malformed one. */
  serve(frame: Buffer, socket: net.Socket, ctx: JobContext): Buffer {
    const u = decodeUserdata(frame);
    const sub = u.params.subfunction;
    const refuse = (errorCode: number) => encodeUserdataResponse(u.pduRef, UserdataGroup.Cyclic, sub, { errorCode });
    if (!this.limits) return refuse(SERVICE_CODE.NOT_IMPLEMENTED);
    if (sub === CyclicSubfunction.Unsubscribe) {
      const { func, jobId } = decodeCyclicUnsubscribe(u.data);
      if (func !== UNSUBSCRIBE_ONE_JOB) return refuse(SERVICE_CODE.SYNTAX);
      if (!this.end(socket, jobId)) return refuse(CYCLIC_ERRORS.NO_SUCH_JOB);
      return encodeUserdataResponse(u.pduRef, UserdataGroup.Cyclic, sub, { sequence: jobId });
    }
    if (sub !== CyclicSubfunction.Memory && sub !== CyclicSubfunction.ChangeDriven) return refuse(SERVICE_CODE.NOT_IMPLEMENTED);
    const job = decodeCyclicSubscribe(sub, u.data);
    const period = (CYCLIC_TIME_BASE_MS[job.timeBase] ?? 0) * job.factor;
    if (period === 0 || period < this.limits.minPeriodMs || period > this.limits.maxPeriodMs) return refuse(CYCLIC_ERRORS.BAD_CYCLE);
    if (this.running >= this.limits.maxJobs) return refuse(CYCLIC_ERRORS.NO_MORE_JOBS);
    const first = readItems(job, ctx);
    if (typeof first === 'number') return refuse(first);
    const jobs = this.jobsOf(socket);
    const jobId = freeId(jobs);
    if (jobId === 0) return refuse(CYCLIC_ERRORS.NO_MORE_JOBS);
    const values = encodeCyclicValues(first);
    const running: Running = { job, last: values, timer: setInterval(() => this.tick(socket, jobId, running, ctx), period) };
    jobs.set(jobId, running);
    this.running++;
    return encodeCyclicAnswer(u.pduRef, sub, jobId, values);
  }

  /** Ends every job (the server closes). */
  close(): void {
    for (const socket of [...this.byConnection.keys()]) this.endAll(socket);
  }

  private jobsOf(socket: net.Socket): Map<number, Running> {
    let jobs = this.byConnection.get(socket);
    if (!jobs) {
      jobs = new Map();
      this.byConnection.set(socket, jobs);
      // A CPU forgets a closed connection's jobs.
      socket.once('close', () => this.endAll(socket));
    }
    return jobs;
  }

  private tick(socket: net.Socket, jobId: number, r: Running, ctx: JobContext): void {
    if (socket.destroyed) return this.endAll(socket);
    const items = readItems(r.job, ctx);
    if (typeof items === 'number') return;
    const values = encodeCyclicValues(items);
    if (r.job.subfunction === CyclicSubfunction.ChangeDriven && r.last?.equals(values)) return;
    r.last = values;
    socket.write(encodeCyclicPush(r.job.subfunction, jobId, values));
  }

  private end(socket: net.Socket, jobId: number): boolean {
    const jobs = this.byConnection.get(socket);
    const r = jobs?.get(jobId);
    if (!jobs || !r) return false;
    clearInterval(r.timer);
    jobs.delete(jobId);
    this.running--;
    return true;
  }

  private endAll(socket: net.Socket): void {
    const jobs = this.byConnection.get(socket);
    if (!jobs) return;
    for (const id of [...jobs.keys()]) this.end(socket, id);
    this.byConnection.delete(socket);
  }
}

/** The lowest job id (1..255) a connection does not use, or 0. */
function freeId(jobs: Map<number, Running>): number {
  for (let id = 1; id <= 255; id++) if (!jobs.has(id)) return id;
  return 0;
}

/** The job's items read as a Read Var reads them; a number: the error the whole job is refused with. */
function readItems(job: CyclicJob, ctx: JobContext): ReadResponseItem[] | number {
  if (job.items.length > 255) return SERVICE_CODE.SYNTAX;
  const ack = decodeS7(serveRead(encodeReadRequest(0, job.items), { ...ctx, pduSize: ctx.pduSize - CYCLIC_EXTRA }));
  if (ack.kind === 'error') return (ack.errorClass << 8) | ack.errorCode;
  return ack.kind === 'read-ack' ? ack.items : SERVICE_CODE.SYNTAX;
}
