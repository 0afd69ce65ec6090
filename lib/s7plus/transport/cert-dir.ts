/**
 * The simulator's certificate kept in a directory the user names
 * (`plcwire serve s7 --tls-dir DIR`, the demo's per-user directory): made on
 * the first start, the same on every start after, so a client that pinned its
 * fingerprint still trusts it after a restart (issue #31). The key file is
 * readable by its owner alone (mode 0600, the directory 0700), as OpenSSH
 * keeps a private key, and the directory is never inside this package: an
 * install would wipe it, and a key in a clone is one `git add` from public.
 */
import * as fs from 'node:fs';
import * as path from 'node:path';
import { ValueError } from '../../errors';
import { generateCertificate, type CertificateOptions } from './cert';
import { loadServerCertificate, type ServerCertificate } from './server-tls';

/** The file names in a certificate directory. */
export const CERTIFICATE_FILES = Object.freeze({ cert: 'cert.pem', key: 'key.pem' });

/** Mode bits of a key file no one but its owner may read or write. */
const KEY_MODE = 0o600;
const DIR_MODE = 0o700;

/** The directory of this package (the nearest holding its package.json), which a certificate directory must be outside. */
function packageRoot(): string {
  let dir = __dirname;
  while (!fs.existsSync(path.join(dir, 'package.json')) && path.dirname(dir) !== dir) dir = path.dirname(dir);
  return fs.realpathSync(dir);
}

/** True when `dir` is `root` or below it. */
function inside(dir: string, root: string): boolean {
  const rel = path.relative(root, dir);
  return rel === '' || (!rel.startsWith('..') && !path.isAbsolute(rel));
}

/** `dir` resolved through symbolic links as far as it exists (the rest as given). */
function realPath(dir: string): string {
  const absolute = path.resolve(dir);
  let existing = absolute;
  while (!fs.existsSync(existing) && path.dirname(existing) !== existing) existing = path.dirname(existing);
  return path.join(fs.realpathSync(existing), path.relative(existing, absolute));
}

/**
 * The certificate and key kept in `dir` (`cert.pem`, `key.pem`): read when both are there (checked to belong
 * together, the key's mode 0600 on POSIX), else made (`generate`: its options) and written, the key with mode 0600,
 * never over an existing file. A ValueError names the flag (`what`), the file and what is wrong.
 */
export async function certificateInDirectory(
  dir: string,
  generate: CertificateOptions = {},
  what = '--tls-dir',
): Promise<ServerCertificate> {
  const where = realPath(dir);
  const root = packageRoot();
  if (inside(where, root))
    throw new ValueError(what, `${dir} is inside the plcwire package (${root}); name a directory of your own, outside it`);
  const certFile = path.join(where, CERTIFICATE_FILES.cert);
  const keyFile = path.join(where, CERTIFICATE_FILES.key);
  const have = [certFile, keyFile].filter((f) => fs.existsSync(f));
  if (have.length === 1) {
    const missing = have[0] === certFile ? keyFile : certFile;
    throw new ValueError(what, `${have[0]} is there but ${missing} is not: put it back, or remove both to make a new certificate`);
  }
  if (have.length === 2) {
    checkKeyMode(keyFile, what);
    const kept = await loadServerCertificate({ certFile, keyFile });
    return { ...kept, source: `kept in ${where}` };
  }
  try {
    fs.mkdirSync(where, { recursive: true, mode: DIR_MODE });
  } catch (err) {
    throw new ValueError(what, `cannot make ${where} (${(err as NodeJS.ErrnoException).code ?? (err as Error).message})`);
  }
  const made = await generateCertificate(generate);
  try {
    // 'wx': never over a file another start wrote in the meantime; the key first, so a cert never stands without it.
    fs.writeFileSync(keyFile, made.key, { mode: KEY_MODE, flag: 'wx' });
    fs.writeFileSync(certFile, made.cert, { mode: 0o644, flag: 'wx' });
  } catch (err) {
    throw new ValueError(
      what,
      `cannot write the certificate into ${where} (${(err as NodeJS.ErrnoException).code ?? (err as Error).message})`,
    );
  }
  return { cert: made.cert, key: made.key, fingerprint: made.fingerprint, source: `made and kept in ${where}` };
}

/** A key file others can read is refused, as OpenSSH refuses an unprotected private key (POSIX modes only). */
function checkKeyMode(keyFile: string, what: string): void {
  if (process.platform === 'win32') return;
  const mode = fs.statSync(keyFile).mode & 0o777;
  if ((mode & 0o077) !== 0) {
    throw new ValueError(what, `${keyFile} can be read by others (mode ${mode.toString(8).padStart(4, '0')}): chmod 600 it`);
  }
}
