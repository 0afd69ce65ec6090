/**
 * The S7CommPlus side of `plcwire serve s7` for an S7-1200/1500 profile
 * (composed with the S7 simulator in lib/cpu/serve.ts): the certificate given
 * with --tls-cert/--tls-key, kept in --tls-dir (made on its first start), or
 * one generated at start (the package ships no private key), and the program
 * from --source.
 */
import type { ServeFlags } from '../../sim/serve';
import { ValueError } from '../../errors';
import { generateCertificate } from '../transport/cert';
import { certificateInDirectory } from '../transport/cert-dir';
import { S7PlusService, type S7PlusOptions } from './index';
import type { AlarmDefinition } from '../../alarms/model';

const SIMULATOR_CERTIFICATE = Object.freeze({ commonName: 'plcwire simulator' });

/** The certificate kept in --tls-dir (made on the first start); what is wrong with the directory is a usage error. */
async function keptCertificate(flags: ServeFlags, dir: string): Promise<{ cert: string; key: string }> {
  try {
    const { cert, key } = await certificateInDirectory(dir, SIMULATOR_CERTIFICATE);
    return { cert, key };
  } catch (err) {
    if (err instanceof ValueError) throw flags.usage(err.message);
    throw err;
  }
}

/** The S7CommPlus service `plcwire serve s7` adds to an S7-1200/1500 (lib/cpu/serve.ts), from the command line's flags. */
export async function servePlus(flags: ServeFlags, alarms?: readonly AlarmDefinition[]): Promise<S7PlusService> {
  const certFile = flags.string('tls-cert');
  const keyFile = flags.string('tls-key');
  const passwordFile = flags.string('password-file');
  const tlsDir = flags.string('tls-dir');
  if ((certFile === undefined) !== (keyFile === undefined))
    throw flags.usage('--tls-cert and --tls-key go together: the certificate and its private key (PEM)');
  if (tlsDir !== undefined && certFile !== undefined)
    throw flags.usage('--tls-dir keeps a certificate the simulator makes, --tls-cert/--tls-key give yours: one or the other');
  const tls =
    certFile !== undefined && keyFile !== undefined
      ? { cert: flags.readFile(certFile), key: flags.readFile(keyFile) }
      : tlsDir !== undefined
        ? await keptCertificate(flags, tlsDir)
        : await generateCertificate(SIMULATOR_CERTIFICATE).then((c) => ({ cert: c.cert, key: c.key }));
  // The password: the file's first line, never printed.
  const password = passwordFile === undefined ? undefined : flags.readFile(passwordFile).toString('utf8').split(/\r?\n/)[0]!;
  if (password === '') throw flags.usage(`--password-file ${passwordFile}: the file's first line is empty; it holds the CPU's password`);
  const files = flags.sourceFiles();
  try {
    // The alarm definitions (--alarms) go to the service as `alarms` (its Program_Alarms: issue #33).
    const options: S7PlusOptions & { alarms?: readonly AlarmDefinition[] } = {
      sources: files?.sources ?? [],
      ...(files ? { db: files.db } : {}),
      tls,
      ...(password === undefined ? {} : { password }),
      ...(alarms ? { alarms } : {}),
    };
    return new S7PlusService(options);
  } catch (err) {
    if (err instanceof Error && /certificate|key|PEM|asn1/i.test(err.message) && certFile !== undefined) {
      throw flags.usage(`--tls-cert ${certFile} / --tls-key ${keyFile}: not a certificate and its key in PEM (${err.message})`);
    }
    throw err;
  }
}
