/** A small argv parser: positionals plus --flag, --flag value and --flag=value. */
import type { Endpoint } from '../url';

export interface ParsedArgs {
  positionals: string[];
  /** Each flag given; a value flag given twice holds its last value. */
  flags: Map<string, string | true>;
  /** Every value of each value flag, in order (for the repeatable ones: --db, --symbols, --source). */
  lists: Map<string, string[]>;
}

export class UsageError extends Error {}

export function parseArgs(argv: readonly string[], valueFlags: readonly string[], boolFlags: readonly string[]): ParsedArgs {
  const positionals: string[] = [];
  const flags = new Map<string, string | true>();
  const lists = new Map<string, string[]>();
  for (let i = 0; i < argv.length; i++) {
    const arg = argv[i]!;
    if (arg === '--') {
      positionals.push(...argv.slice(i + 1));
      break;
    }
    if (!arg.startsWith('--')) {
      positionals.push(arg);
      continue;
    }
    const eq = arg.indexOf('=');
    const name = arg.slice(2, eq < 0 ? undefined : eq);
    if (boolFlags.includes(name)) {
      if (eq >= 0) throw new UsageError(`--${name} takes no value`);
      flags.set(name, true);
    } else if (valueFlags.includes(name)) {
      const value = eq >= 0 ? arg.slice(eq + 1) : argv[++i];
      if (value === undefined) throw new UsageError(`--${name} needs a value`);
      flags.set(name, value);
      lists.set(name, [...(lists.get(name) ?? []), value]);
    } else if (name === 'password') {
      // Never echoed: the value is the secret. A command line is visible to every user of the machine (ps).
      throw new UsageError('--password is not an option: give the password in PLCWIRE_PASSWORD or with --password-file FILE');
    } else {
      throw new UsageError(`unknown option --${name}`);
    }
  }
  return { positionals, flags, lists };
}

export function intFlag(args: ParsedArgs, name: string, fallback: number, min = 0, max = Number.MAX_SAFE_INTEGER): number {
  const raw = args.flags.get(name);
  if (raw === undefined) return fallback;
  if (raw === true || !/^\d+$/.test(raw)) throw new UsageError(`--${name} takes a whole number`);
  const n = Number(raw);
  if (n < min || n > max) throw new UsageError(`--${name} must be between ${min} and ${max}`);
  return n;
}

export function stringFlag(args: ParsedArgs, name: string): string | undefined {
  const raw = args.flags.get(name);
  return raw === true ? undefined : raw;
}

/** Every value of a repeatable flag, in the order given; [] when absent. */
export function listFlag(args: ParsedArgs, name: string): string[] {
  return args.lists.get(name) ?? [];
}

/** The endpoint with --timeout applied, when given. */
export function withTimeout<E extends Endpoint>(endpoint: E, args: ParsedArgs): E {
  if (!args.flags.has('timeout')) return endpoint;
  return { ...endpoint, timeout: intFlag(args, 'timeout', endpoint.timeout, 1, 600_000) };
}
