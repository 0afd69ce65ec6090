/**
 * A node's tag table made ready for polling, once per table: the address list
 * the client is given on every poll, and builders for what a read of the
 * whole table turns into when every tag succeeded (the common case, which
 * must cost little: a Node-RED read node runs it every poll).
 *
 * Every builder returns fresh objects: a flow's nodes may change the message
 * they receive, so no object is shared between two messages or two polls.
 * Objects of a hundred keys built key by key turn into hash tables; an object
 * literal is built in one step, so the builders are compiled to literals
 * (with a plain loop as fallback where code generation is disabled).
 */
import type { TagRow } from '../tags/table';

type Values = Readonly<Record<string, unknown>>;
type Build<T> = (values: Values) => T;

export class PolledTable {
  readonly tags: readonly TagRow[];
  /** Each address once, in table order: pass this same array to every read (the client keeps its plan for it). */
  readonly addresses: readonly string[];
  /** Per row, the row's name's slot: rows that share a name share a slot (the change filter's memory). */
  readonly slots: readonly number[];
  /** How many distinct names the table has. */
  readonly slotCount: number;
  /** Per row: an earlier row reads the same address (its value is the same object). */
  readonly repeated: readonly boolean[];
  /** `msg.payload` of a good read: { name: value }. */
  readonly payload: Build<Record<string, unknown>>;
  /** `msg.quality` of a good read: { name: 'good' }. */
  readonly goodQuality: () => Record<string, string>;
  /** `msg.addresses`: { name: address }. */
  readonly addressesByName: () => Record<string, string>;
  /** The rows' values in row order. */
  readonly rowValues: Build<unknown[]>;

  constructor(tags: readonly TagRow[]) {
    this.tags = tags;
    const slotOf = new Map<string, number>();
    const seen = new Set<string>();
    this.slots = tags.map(({ name }) => {
      let slot = slotOf.get(name);
      if (slot === undefined) slotOf.set(name, (slot = slotOf.size));
      return slot;
    });
    this.slotCount = slotOf.size;
    this.repeated = tags.map(({ address }) => seen.has(address) || (seen.add(address), false));
    this.addresses = [...seen];
    // With a name given twice, the key-by-key loop's result (last row wins, payload only from good rows) is kept.
    const compile = slotOf.size === tags.length && !slotOf.has('__proto__') ? compiled : noCompile;
    const key = JSON.stringify;
    const fields = (value: (t: TagRow, i: number) => string) => tags.map((t, i) => `${key(t.name)}: ${value(t, i)}`).join(',\n');
    this.payload =
      compile<Build<Record<string, unknown>>>('values', `return {${fields((t) => `values[${key(t.address)}]`)}};`) ??
      ((values) => {
        const out: Record<string, unknown> = {};
        for (const t of tags) put(out, t.name, values[t.address]);
        return out;
      });
    this.goodQuality =
      compile<() => Record<string, string>>('', `return {${fields(() => `'good'`)}};`) ??
      (() => {
        const out: Record<string, string> = {};
        for (const t of tags) put(out, t.name, 'good');
        return out;
      });
    this.addressesByName =
      compile<() => Record<string, string>>('', `return {${fields((t) => key(t.address))}};`) ??
      (() => {
        const out: Record<string, string> = {};
        for (const t of tags) put(out, t.name, t.address);
        return out;
      });
    this.rowValues =
      compiled<Build<unknown[]>>('values', `return [${tags.map((t) => `values[${key(t.address)}]`).join(',\n')}];`) ??
      ((values) => tags.map((t) => values[t.address]));
  }
}

/** `out[key] = value`, also for a tag named __proto__ (an own key, not the object's prototype). */
function put<T>(out: Record<string, T>, key: string, value: T): void {
  if (key === '__proto__') Object.defineProperty(out, key, { value, enumerable: true, writable: true, configurable: true });
  else out[key] = value;
}

/** A function from source, or undefined where code generation is disabled (--disallow-code-generation-from-strings). */
function compiled<F>(parameter: string, body: string): F | undefined {
  try {
    // eslint-disable-next-line @typescript-eslint/no-implied-eval -- the bodies are built from JSON-quoted keys (see the callers)
    return new Function(parameter, body) as F;
  } catch {
    return undefined;
  }
}

const noCompile: typeof compiled = () => undefined;
