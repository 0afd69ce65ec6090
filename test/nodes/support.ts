/**
 * What the node tests share: the test helper on the Node-RED of this run
 * (PLCWIRE_NODE_RED selects Node-RED 5), our node modules, the core Catch and
 * Status nodes, simulators behind one small interface, and deadline waits.
 */
import * as asyncHooks from 'node:async_hooks';
import * as path from 'node:path';

export const ROOT = path.resolve(__dirname, '../../..');
const NODES_DIR = path.join(ROOT, 'nodes') + path.sep;
const LIB_DIR = path.join(ROOT, 'dist', 'lib') + path.sep;
export const RED_PATH = require.resolve(process.env.PLCWIRE_NODE_RED || 'node-red');
/** Node-RED's core nodes (catch, status, tls-config) of the Node-RED this run uses. */
export const CORE_NODES = path.dirname(require.resolve('@node-red/nodes/package.json', { paths: [path.dirname(RED_PATH)] }));
const CORE = CORE_NODES;

export const helper: any = require('node-red-node-test-helper');
helper.init(RED_PATH);

export const nodes = {
  connection: require(path.join(ROOT, 'nodes/connection.js')),
  read: require(path.join(ROOT, 'nodes/read.js')),
  write: require(path.join(ROOT, 'nodes/write.js')),
  heartbeat: require(path.join(ROOT, 'nodes/heartbeat.js')),
  control: require(path.join(ROOT, 'nodes/control.js')),
  alarms: require(path.join(ROOT, 'nodes/alarms.js')),
  catch: require(path.join(CORE, 'core/common/25-catch.js')),
  status: require(path.join(CORE, 'core/common/25-status.js')),
};
export const ALL_NODES = Object.values(nodes);

/** A simulated PLC with word-sized integer slots 0..5 the tests poke and peek. */
export interface Sim {
  readonly protocol: string;
  readonly url: string;
  /** Address of integer slot i, in the protocol's syntax. */
  addr(i: number): string;
  set(i: number, value: number): void;
  get(i: number): number;
  /** An address the PLC refuses (no such data block / station). */
  readonly missing: string;
  connectionCount(): number;
  /** Stops the PLC (drops every client); restart() brings it back on the same port and memory. */
  stop(): Promise<void>;
  restart(): Promise<void>;
  close(): Promise<void>;
}

export type SimFactory = () => Promise<Sim>;

/** Collects the messages a helper node receives; `next` waits for one with a deadline. */
export class Recorder {
  readonly messages: any[] = [];
  private cursor = 0;
  private wake: (() => void) | undefined;

  constructor(node: any) {
    node.on('input', (msg: any) => {
      this.messages.push(msg);
      this.wake?.();
    });
  }

  /** The next message (after those already taken) that satisfies `match`; earlier non-matching ones are skipped. */
  async next(match: (msg: any) => boolean = () => true, ms = 4000, what = 'a message'): Promise<any> {
    const deadline = Date.now() + ms;
    for (;;) {
      while (this.cursor < this.messages.length) {
        const msg = this.messages[this.cursor++];
        if (match(msg)) return msg;
      }
      const left = deadline - Date.now();
      if (left <= 0) throw new Error(`no ${what} within ${ms} ms (got ${this.messages.length}: ${summary(this.messages.slice(-3))})`);
      await new Promise<void>((resolve) => {
        const timer = setTimeout(resolve, left);
        this.wake = () => {
          clearTimeout(timer);
          this.wake = undefined;
          resolve();
        };
      });
    }
  }

  /** Skips everything received so far. */
  skip(): void {
    this.cursor = this.messages.length;
  }
}

function summary(msgs: any[]): string {
  return msgs.map((m) => JSON.stringify(m, (_k, v) => (typeof v === 'bigint' ? `${v}n` : v)).slice(0, 200)).join(' | ');
}

/** Polls `condition` until it holds or the deadline passes (for state with no event, e.g. a server's connection count). */
export async function until(condition: () => boolean, ms = 4000, what = 'condition'): Promise<void> {
  const deadline = Date.now() + ms;
  while (!condition()) {
    if (Date.now() > deadline) throw new Error(`${what} did not hold within ${ms} ms`);
    await new Promise((r) => setTimeout(r, 10));
  }
}

/**
 * Timers created by our code (the nodes and the library) that are still
 * pending: a leak check that ignores the test helper's own HTTP server timers.
 */
export class OurTimers {
  private readonly live = new Map<number, string>();
  private readonly hook = asyncHooks.createHook({
    init: (id, type) => {
      if (type !== 'Timeout') return;
      const stack = new Error().stack ?? '';
      const ours = stack.split('\n').find((line) => line.includes(NODES_DIR) || line.includes(LIB_DIR));
      if (ours) this.live.set(id, ours.trim());
    },
    destroy: (id) => void this.live.delete(id),
  });

  start(): this {
    this.hook.enable();
    return this;
  }

  stop(): void {
    this.hook.disable();
  }

  get count(): number {
    return this.live.size;
  }

  describe(): string {
    return [...this.live.values()].join('; ');
  }
}
