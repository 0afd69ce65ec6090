/**
 * Password protection of the simulated CPU: with a password its access
 * level is "read access" (protocol.py AccessLevel 2: reads, no writes) until
 * the session legitimates. The "new" legitimation of firmware from S7-1500
 * V3.1 / S7-1200 V4.7 (legitimation.py): the CPU gives a challenge, the
 * client sends its credentials encrypted with AES-256-CBC, key SHA-256 of the
 * TLS exporter secret "EXPERIMENTAL_OMS" (32 bytes), IV the challenge's first
 * 16 bytes; the key rolls (SHA-256 again) after every attempt. Credentials:
 * Struct 40400 of type 40401, user 40402 and password 40403 (a SHA-1 of it
 * when the user is empty). The "legacy" form of S7-1500 V2.9-V3.0 and
 * S7-1200 V4.3-V4.6 (the CPU's device string decides, `device` of the
 * service): SHA-1 of the password XOR the challenge, written to 304. The
 * password is compared, never logged.
 */
import { createDecipheriv, createHash, randomBytes, timingSafeEqual } from 'node:crypto';
import { decodeCredentials, legitimationForm, type LegitimationForm } from '../codec/legitimation';
import { AccessLevel, LegitimationType } from '../constants';

/** The level of a session that may write (protocol.py AccessLevel). */
export const FULL_ACCESS = AccessLevel.FullAccess;

export class Legitimation {
  private challenge: Buffer | undefined;
  private secret: Buffer | undefined;
  level: number;

  /** The form the CPU's firmware takes (codec/legitimation.ts legitimationForm); the other one is refused. */
  private readonly form: LegitimationForm | undefined;

  /** Compared, never shown: a private field (no inspect() of the simulator's sessions shows it). */
  readonly #password: string | undefined;

  constructor(
    password: string | undefined,
    /** The TLS exporter secret of the connection, undefined without TLS. */
    private readonly exporter: () => Buffer | undefined,
    /** The device string of the CPU's ServerSessionVersion. */
    device: string,
  ) {
    this.#password = password;
    this.level = password === undefined ? AccessLevel.FullAccess : AccessLevel.ReadAccess;
    this.form = legitimationForm(device);
  }

  /**
   * The legacy form's answer: true when it is the SHA-1 of the password XOR
   * the challenge (legitimation.py build_legacy_response); a CPU of the new
   * form refuses it.
   */
  attemptLegacy(answer: Buffer): boolean {
    const challenge = this.challenge;
    this.challenge = undefined;
    if (this.#password === undefined) return true;
    if (this.form !== 'legacy' || !challenge || answer.length !== 20 || challenge.length < 20) return false;
    const hash = createHash('sha1').update(this.#password, 'utf8').digest();
    const expected = Buffer.from(hash.map((b, i) => b ^ challenge[i]!));
    const ok = timingSafeEqual(expected, answer);
    if (ok) this.level = AccessLevel.FullAccess;
    return ok;
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
    if (this.#password === undefined) return true;
    if (this.form !== 'new') return false;
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
        ? createHash('sha1').update(this.#password, 'utf8').digest()
        : Buffer.from(this.#password, 'utf8');
    const ok = expected.length === credentials.password.length && timingSafeEqual(expected, credentials.password);
    if (ok) this.level = AccessLevel.FullAccess;
    return ok;
  }
}
