/**
 * S7CommPlus on the command line: the PLC's password and `plcwire browse`.
 *
 * The password of an s7plus:// connection comes from the PLCWIRE_PASSWORD
 * environment variable or from the first line of `--password-file FILE`;
 * never from the URL (the URL parser refuses `password=`) or a flag's value
 * (`--password` is refused: every user of the machine sees a command line).
 * It goes to the client as ConnectOptions.password and nowhere else: no
 * message of this file quotes it.
 */
import type { AnyClient, ConnectOptions } from '../connect';
import { ValueError } from '../errors';
import type { SymbolEntry, SymbolTable } from '../symbols/model';
import { wholeBlock } from '../symbols/resolve';
import { unknownName } from '../s7plus/client/names';
import { entryTree, expandStruct } from '../symbols/struct-tree';
import { parseUrl, type Endpoint } from '../url';
import { UsageError, stringFlag, withTimeout, type ParsedArgs } from './args';
import { readInputFile } from './files';
import { EXIT, withClient, type CliIo } from './io';
import { printSymbolRows } from './symbols';
import { valueFromText, type TypedTag } from './values';
import { validateValue, type TagShape } from '../values';
import { createClient } from '../connect';
import { driverOf, schemesOffering } from '../drivers';

/** The environment variable that gives an s7plus:// connection its password. */
const PASSWORD_ENV = 'PLCWIRE_PASSWORD';

/**
 * The password option of `endpoint`: `--password-file` (its first line, the
 * line end trimmed) before PLCWIRE_PASSWORD; none for a URL that is not
 * s7plus:// (the file given with one is a usage error: nothing would use it).
 */
export function passwordOption(
  endpoint: Endpoint,
  args: ParsedArgs,
  env: NodeJS.ProcessEnv = process.env,
): Pick<ConnectOptions, 'password'> {
  const file = stringFlag(args, 'password-file');
  if (args.flags.has('password-file') && file === undefined) throw new UsageError('--password-file needs a file name');
  if (!driverOf(endpoint).password) {
    if (file !== undefined)
      throw new UsageError(`--password-file is for ${schemesOffering('password')} URLs; ${endpoint.protocol}:// has no password`);
    return {};
  }
  if (file !== undefined) return { password: secretFromFile('password-file', file) };
  const fromEnv = env[PASSWORD_ENV];
  return fromEnv === undefined || fromEnv === '' ? {} : { password: fromEnv };
}

/** A password kept in `file` (its first line, the line end trimmed) of option --`name`; errors name the file, never its content. */
export function secretFromFile(name: string, file: string): string {
  let text: string;
  try {
    text = readInputFile(file).toString('utf8');
  } catch (err) {
    // Why (no such file, no permission) and the file's name; nothing of its content.
    throw new UsageError(`--${name}: ${(err as Error).message}`);
  }
  const first = text.replace(/^\uFEFF/, '').split(/\r?\n/, 1)[0] ?? '';
  if (first === '') throw new UsageError(`--${name} ${file}: its first line is empty (the password is the first line)`);
  return first;
}

/** `plcwire browse <url> [--json]`: the PLC's tags as `plcwire symbols` lists compiled ones. */
export async function browse(rest: string[], args: ParsedArgs, io: CliIo): Promise<number> {
  const url = rest[0];
  if (url === undefined) throw new UsageError(`browse needs an ${schemesOffering('browse')} url`);
  if (rest.length > 1) throw new UsageError(`unexpected argument "${rest[1]}"`);
  if (args.flags.has('csv') && args.flags.has('json')) throw new UsageError('give --json or --csv, not both');
  const endpoint = withTimeout(parseUrl(url), args);
  const driver = driverOf(endpoint);
  if (!driver.browse) {
    throw new UsageError(
      `browse asks the PLC for its tags: give an ${schemesOffering('browse')} URL (for ${endpoint.protocol}://, list the sources with plcwire symbols)`,
    );
  }
  const client = createClient(endpoint, passwordOption(endpoint, args));
  const table = await withClient(client, io, (c) => driver.browse!(c, { signal: io.signal }));
  printSymbolRows(table, args, io);
  return EXIT.OK;
}

/**
 * True when `address` is, for this client, a name of the PLC's own program (an s7plus:// client without sources:
 * client/names.ts plusSyntax), whose type only the browse tells.
 */
export function isPlcName(client: AnyClient, address: string): boolean {
  if (!driverOf(client).browse) return false;
  return typeof (client.tag(address) as { symbol?: unknown }).symbol === 'string';
}

/**
 * The value of `text` for the name `address` of a browsed table: an elementary member's text parsed by its type, as
 * an address's is (a REAL's 40.4, a STRING's text); a struct or array as JSON keyed by member name (an array as a
 * JSON array). A name the PLC does not have is refused, naming the closest names.
 */
export function browsedValueFromText(table: SymbolTable, address: string, text: string): unknown {
  const entry = table.lookup(address) ?? wholeBlock(table, address);
  // A name the PLC does not have is refused with the closest names before anything is sent.
  if (!entry) throw unknownName(table, address);
  if (entry.kind === 'elementary' && entry.dataType) {
    const tag = leafTag(entry);
    const value = valueFromText(tag, text);
    validateValue(tag, value);
    return value;
  }
  let value: unknown;
  try {
    value = JSON.parse(text) as unknown;
  } catch {
    const example = entry.kind === 'array' ? 'a JSON array, e.g. [1, 2, 3]' : 'an object keyed by member name, e.g. {"Speed": 1.5}';
    throw new ValueError(address, `"${text}" is not JSON (a ${entry.type} is written as ${example})`);
  }
  // Every member's value checked now, before anything is sent (a struct partly given writes the members it names).
  expandStruct(entryTree(table, entry), value, (leaf, v) => leaf.entry.dataType && validateValue(leafTag(leaf.entry), v));
  return value;
}

/** An elementary entry as the value codecs see it. */
function leafTag(entry: SymbolEntry): TypedTag & TagShape {
  return {
    address: entry.name,
    type: entry.dataType!,
    count: 1,
    isArray: false,
    stringLength: entry.stringLength,
    bitOffset: 0,
  } as TypedTag & TagShape;
}
