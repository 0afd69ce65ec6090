/**
 * What a read node sends for a read: one builder for both ways a read ends.
 * A read of the configured table in which every tag succeeded (the common
 * case) takes a short way: the client's values by address, turned into
 * messages by the table's builders (PolledTable), with no per-tag outcome
 * objects. A read with a failed tag, or of on-demand addresses, comes as
 * per-tag outcomes. Both make their messages here, with the same fields.
 *
 * Every message sent is a fresh object, one send() each: nothing a
 * downstream node changes in one message shows in another (the runtime
 * clones none of them). The messages of one read share one _msgid, as those
 * of one send([msgs]) call do.
 */
import type { ChangeFilter } from './change-filter';
import type { TagErrorInfo, TagOutcome } from './outcome';
import type { PolledTable } from './polled-table';

/** A flow message: the input message a read answers, or a new one. */
export type FlowMessage = Record<string, unknown>;

/** 'object': one message per read; 'per-tag': one per tag; 'changes': one per tag that changed. */
export type ReadOutput = 'object' | 'per-tag' | 'changes';

/** What the flow runtime provides: a deep copy of a message and a new message id (Node-RED's RED.util). */
export interface MessageRuntime {
  clone(msg: FlowMessage): FlowMessage;
  newId(): string;
}

type Send = (msg: FlowMessage) => void;

/** The output mode a node configures ('object' for anything else). */
export function readOutput(value: unknown): ReadOutput {
  return value === 'per-tag' || value === 'changes' ? value : 'object';
}

/**
 * The message of one tag: on `base` (the input message, changed in place) or
 * a new one with `id` as its _msgid (none when undefined). `error` undefined
 * means the tag was read and `value` is its value.
 */
function tagMessage(
  name: string,
  address: string,
  value: unknown,
  error: TagErrorInfo | undefined,
  base: FlowMessage | undefined,
  id: string | undefined,
): FlowMessage {
  if (!base) {
    let msg: FlowMessage;
    if (error) msg = { topic: name, address, payload: null, quality: 'bad', errors: { [name]: error } };
    else if (id) return { topic: name, address, payload: value, quality: 'good', _msgid: id };
    else msg = { topic: name, address, payload: value, quality: 'good' };
    if (id) msg._msgid = id;
    return msg;
  }
  base.topic = name;
  base.address = address;
  base.payload = error ? null : value;
  base.quality = error ? 'bad' : 'good';
  if (error) base.errors = { [name]: error };
  else delete base.errors;
  return base;
}

/** The one message of a read in 'object' output, on `base` or a new one with `topic`. */
function objectMessage(
  payload: Record<string, unknown>,
  quality: Record<string, string>,
  addresses: Record<string, string>,
  errors: Record<string, TagErrorInfo> | undefined,
  base: FlowMessage | undefined,
  topic: string,
): FlowMessage {
  if (!base && !errors) return { payload, quality, addresses, topic };
  const msg = base || {};
  msg.payload = payload;
  msg.quality = quality;
  msg.addresses = addresses;
  if (errors) msg.errors = errors;
  else delete msg.errors;
  if (!base) msg.topic = topic;
  return msg;
}

export class ReadMessages {
  /**
   * `table`: the node's configured table; `topic`: the topic of an object
   * message that answers no input; `changes`: the node's memory of what it
   * reported ('changes' output).
   */
  constructor(
    private readonly table: PolledTable,
    private readonly output: ReadOutput,
    private readonly topic: string,
    private readonly changes: ChangeFilter,
    private readonly runtime: MessageRuntime,
  ) {}

  /** Sends a read of the whole table in which every tag succeeded (`values` by address), answering `base` if given. */
  sendGood(send: Send, values: Readonly<Record<string, unknown>>, base?: FlowMessage): void {
    const { table, runtime } = this;
    if (this.output === 'object') {
      send(objectMessage(table.payload(values), table.goodQuality(), table.addressesByName(), undefined, base, this.topic));
      return;
    }
    const row = table.rowValues(values);
    const rows = this.output === 'changes' ? this.changes.changedRows(table, row) : undefined;
    const n = rows ? rows.length : row.length;
    if (n === 0) return;
    const id = base ? undefined : runtime.newId();
    for (let k = 0; k < n; k++) {
      const i = rows ? rows[k]! : k;
      const t = table.tags[i]!;
      const msg = tagMessage(t.name, t.address, row[i], undefined, base && k < n - 1 ? runtime.clone(base) : base, id);
      // Two rows of one address read one value: the later row's message gets its own copy.
      send(table.repeated[i] ? runtime.clone(msg) : msg);
    }
  }

  /**
   * Sends the outcomes of a read of `list`, answering `base` if given.
   * `onDemand`: the list is not the configured table (it has no history to
   * compare with: 'changes' output sends it one message per tag).
   */
  sendOutcomes(send: Send, list: readonly TagOutcome[], base?: FlowMessage, onDemand = false): void {
    const mode = this.output === 'changes' && onDemand ? 'per-tag' : this.output;
    if (mode === 'object') {
      const payload: Record<string, unknown> = {};
      const quality: Record<string, string> = {};
      const addresses: Record<string, string> = {};
      for (const o of list) {
        quality[o.name] = o.ok ? 'good' : 'bad';
        addresses[o.name] = o.address;
        if (o.ok) payload[o.name] = o.value;
      }
      const bad = list.filter((o) => !o.ok);
      const errors = bad.length > 0 ? Object.fromEntries(bad.map((o) => [o.name, o.error])) : undefined;
      send(objectMessage(payload, quality, addresses, errors, base, this.topic));
      return;
    }
    const out = mode === 'changes' ? this.changes.filter(list) : list;
    const id = base || out.length < 2 ? undefined : this.runtime.newId();
    const seen = new Set<string>();
    out.forEach((o, i) => {
      const on = base ? (i === out.length - 1 ? base : this.runtime.clone(base)) : undefined;
      const msg = tagMessage(o.name, o.address, o.ok ? o.value : undefined, o.ok ? undefined : o.error, on, id);
      // Rows of one address carry one value object: each later row's message gets its own copy, as in sendGood.
      const repeated = seen.has(o.address);
      seen.add(o.address);
      send(repeated && o.ok ? this.runtime.clone(msg) : msg);
    });
  }
}
