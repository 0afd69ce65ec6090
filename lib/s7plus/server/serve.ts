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

/** How often a --source file's size and time are looked at (by path: a file an editor replaced is seen too). */
const WATCH_MS = 500;

/** A file's time and size, or 'missing'. */
function stamp(file: string): string {
  try {
    const st = fs.statSync(file);
    return `${st.mtimeMs} ${st.size}`;
  } catch {
    return 'missing';
  }
}

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
  // Each file's size and time as it is now, taken at once: a change made the moment after this call is seen (fs.watchFile
  // takes its first look later, on its own, and missed a file written in between).
  const seen = new Map(flags.sourcePaths().map((file) => [file, stamp(file)]));
  let looking = false;
  const timer = setInterval(() => {
    if (looking) return;
    looking = true;
    void Promise.all(
      [...seen].map(async ([file, was]) => {
        const now = await fs.promises.stat(file).then(
          (st) => `${st.mtimeMs} ${st.size}`,
          () => 'missing',
        );
        if (now === was) return undefined;
        seen.set(file, now);
        return file;
      }),
    ).then((files) => {
      looking = false;
      const changed = files.filter((f): f is string => f !== undefined);
      if (changed.length > 0) reload(changed.map((file) => `${file} changed`).join(', '));
    });
  }, WATCH_MS);
  timer.unref();
  return () => {
    process.off('SIGHUP', onHangup);
    clearInterval(timer);
  };
}
