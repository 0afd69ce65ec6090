/**
 * The S7CommPlus side of `plcwire serve s7` for an S7-1200/1500 profile:
 * the certificate given with --tls-cert/--tls-key, or one generated at start
 * (the package ships no private key), and the program from --source.
 */
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
