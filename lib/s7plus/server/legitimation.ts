/**
 * Password protection of the simulated CPU: with a password its access
 * level is "read access" (protocol.py AccessLevel 2: reads, no writes) until
 * the session legitimates. The "new" legitimation of firmware from S7-1500
 * V3.1 / S7-1200 V4.7 (legitimation.py): the CPU gives a challenge, the
 * client sends its credentials encrypted with AES-256-CBC, key SHA-256 of the
 * TLS exporter secret "EXPERIMENTAL_OMS" (32 bytes), IV the challenge's first
 * 16 bytes; the key rolls (SHA-256 again) after every attempt. Credentials:
 * Struct 40400 of type 40401, user 40402 and password 40403 (a SHA-1 of it
 * when the user is empty). The password is compared, never logged.
 */
import { createDecipheriv, createHash, randomBytes, timingSafeEqual } from 'node:crypto';
import { decodeCredentials } from '../codec/legitimation';
import { AccessLevel, LegitimationType } from '../constants';

/** The level of a session that may write (protocol.py AccessLevel). */
export const FULL_ACCESS = AccessLevel.FullAccess;

export class Legitimation {
  private challenge: Buffer | undefined;
  private secret: Buffer | undefined;
  level: number;

  constructor(
    private readonly password: string | undefined,
    /** The TLS exporter secret of the connection, undefined without TLS. */
    private readonly exporter: () => Buffer | undefined,
  ) {
    this.level = password === undefined ? AccessLevel.FullAccess : AccessLevel.ReadAccess;
  }

  /** The challenge of this attempt (20 bytes, as a CPU gives). */
  newChallenge(): Buffer {
    this.challenge = randomBytes(20);
    return this.challenge;
  }

  /** An encrypted credentials blob; true when it holds the password (the level is then full access). */
  attempt(blob: Buffer): boolean {
    const challenge = this.challenge;
    this.challenge = undefined;
    if (this.password === undefined) return true;
    this.secret ??= this.exporter();
    if (!challenge || !this.secret) return false;
    const key = createHash('sha256').update(this.secret).digest();
    this.secret = key;
    let plain: Buffer;
    try {
      const decipher = createDecipheriv('aes-256-cbc', key, challenge.subarray(0, 16));
      plain = Buffer.concat([decipher.update(blob), decipher.final()]);
    } catch {
      return false;
    }
    let credentials: { type: number; password: Buffer };
    try {
      credentials = decodeCredentials(plain);
    } catch {
      return false;
    }
    const expected =
      credentials.type === LegitimationType.Legacy
        ? createHash('sha1').update(this.password, 'utf8').digest()
        : Buffer.from(this.password, 'utf8');
    const ok = expected.length === credentials.password.length && timingSafeEqual(expected, credentials.password);
    if (ok) this.level = AccessLevel.FullAccess;
    return ok;
  }
}
