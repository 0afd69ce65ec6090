/**
 * The S7CommPlus side of `plcwire serve s7` for an S7-1200/1500 profile:
 * the certificate given with --tls-cert/--tls-key, or one generated at start
 * (the package ships no private key), and the program from --source, loaded
 * again (a download) on SIGHUP or when a --source file changes.
 */
import * as fs from 'node:fs';
import type { PlcMemory } from '../../sim/memory';
import type { ServeFlags } from '../../sim/serve';
import { generateCertificate } from '../transport/cert';
import { S7PlusService } from './index';

/** The profiles whose CPUs speak S7CommPlus. */
const PLUS_PROFILES: ReadonlySet<string> = new Set(['s7-1200', 's7-1500']);

/** The S7CommPlus service of the profile, or undefined for a CPU without S7CommPlus (the TLS flags are then a usage error). */
export async function servePlus(flags: ServeFlags, profile: string): Promise<S7PlusService | undefined> {
  const certFile = flags.string('tls-cert');
  const keyFile = flags.string('tls-key');
  const passwordFile = flags.string('password-file');
  if (!PLUS_PROFILES.has(profile)) {
    if (certFile !== undefined || keyFile !== undefined || passwordFile !== undefined)
      throw flags.usage(`--tls-cert, --tls-key and --password-file are for an S7-1200 or S7-1500 (S7CommPlus), not ${profile}`);
    return undefined;
  }
  if ((certFile === undefined) !== (keyFile === undefined))
    throw flags.usage('--tls-cert and --tls-key go together: the certificate and its private key (PEM)');
  const tls =
    certFile !== undefined && keyFile !== undefined
      ? { cert: flags.readFile(certFile), key: flags.readFile(keyFile) }
      : await generateCertificate({ commonName: 'plcwire simulator' }).then((c) => ({ cert: c.cert, key: c.key }));
  // The password: the file's first line, never printed.
  const password = passwordFile === undefined ? undefined : flags.readFile(passwordFile).toString('utf8').split(/\r?\n/)[0]!;
  if (password === '') throw flags.usage(`--password-file ${passwordFile}: the file's first line is empty; it holds the CPU's password`);
  const files = flags.sourceFiles();
  try {
    return new S7PlusService({
      sources: files?.sources ?? [],
      ...(files ? { db: files.db } : {}),
      tls,
      ...(password === undefined ? {} : { password }),
    });
  } catch (err) {
    if (err instanceof Error && /certificate|key|PEM|asn1/i.test(err.message) && certFile !== undefined) {
      throw flags.usage(`--tls-cert ${certFile} / --tls-key ${keyFile}: not a certificate and its key in PEM (${err.message})`);
    }
    throw err;
  }
}

/** How often a --source file's size and time are looked at (fs.watchFile: also sees a file an editor replaced). */
const WATCH_MS = 500;

/**
 * Loads the --source files again into `service` (S7PlusService.reload: a download) on SIGHUP and when one of them
 * changes, and says what changed; sources that do not compile leave the running program and say why. Returns the
 * function that stops watching.
 */
export function reloadOnChange(service: S7PlusService, memory: PlcMemory, flags: ServeFlags): () => void {
  const reload = (why: string) => {
    try {
      const files = flags.sourceFiles();
      const before = service.model;
      const after = service.reload(files?.sources ?? [], memory, files?.db);
      const changed = [...after.times].filter(([rid, time]) => before.times.get(rid) !== time).length;
      const gone = [...before.times.keys()].filter((rid) => !after.times.has(rid)).length;
      flags.say(
        changed + gone === 0
          ? `program loaded again (${why}): unchanged`
          : `program loaded again (${why}): ${changed} type objects new or changed, ${gone} gone; clients browse again`,
      );
    } catch (err) {
      flags.say(`program not loaded again (${why}): ${(err as Error).message}; the CPU keeps its program`);
    }
  };
  const onHangup = () => reload('SIGHUP');
  process.on('SIGHUP', onHangup);
  const watched = flags.sourcePaths().map((file) => {
    const listener = (now: fs.Stats, was: fs.Stats) => {
      if (now.mtimeMs !== was.mtimeMs || now.size !== was.size) reload(`${file} changed`);
    };
    fs.watchFile(file, { interval: WATCH_MS, persistent: false }, listener);
    return { file, listener };
  });
  return () => {
    process.off('SIGHUP', onHangup);
    for (const { file, listener } of watched) fs.unwatchFile(file, listener);
  };
}
