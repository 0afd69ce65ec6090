/**
 * Legitimation: the PLC's password, given once per session (every reconnect
 * gives it again), as the "password" step of openS7PlusSession after the
 * session setup. Facts from s7commplus (MIT): connection.py authenticate,
 * _get_effective_protection_level, _get_legitimation_challenge,
 * _send_legitimation_new/_legacy; legitimation.py decide_legitimation_mode,
 * build_new_response, build_legacy_response, derive_legitimation_key.
 *
 *   1. the session's protection level (GetVarSubStreamed of 1842); at full
 *      access (or none configured) there is nothing to give;
 *   2. the form the firmware takes, from the device string of the
 *      ServerSessionVersion: the new one from S7-1500 V3.1 / S7-1200 V4.7,
 *      the legacy one from S7-1500 V2.9 / S7-1200 V4.3 / S7-1507S V21.9;
 *   3. the challenge (GetVarSubStreamed of 303, 20 bytes);
 *   4. the answer (SetVariable): new: the credentials (the password as its
 *      SHA-1, no user) in AES-256-CBC, key SHA-256 of the TLS exporter
 *      secret "EXPERIMENTAL_OMS" (32 bytes), IV the challenge's first 16
 *      bytes, written to 1846; legacy: SHA-1 of the password XOR the
 *      challenge, written to 304;
 *   5. the protection level again: only a lower level proves the password
 *      (a PLC may accept the SetVariable and keep the level).
 *
 * The password is used here and dropped: no error, event or property holds it.
 */
import { createCipheriv, createHash } from 'node:crypto';
import type { TLSSocket } from 'node:tls';
import { PlcError, ProtocolError, type TagResult } from '../../errors';
import type { Tag } from '../../types';
import {
  challengeOf,
  credentialsBlobValue,
  encodeCredentials,
  legacyAnswerValue,
  legitimationForm,
  paomString,
  protectionLevelOf,
  setVariableRefused,
  type LegitimationForm,
} from '../codec/legitimation';
import type { PValue } from '../codec/pvalue';
import { AccessLevel, Ids, LegitimationType, OMS_EXPORTER_LABEL, OMS_EXPORTER_LENGTH } from '../constants';
import { legitimateAsk, sessionAttributeAsk } from './asks';
import type { S7PlusSession } from './session';

/** What the password step found and did: the session's protection level after it, and whether a password lowered it. */
export interface Protection {
  /** AccessLevel: 0 none configured, 1 full access, 2 read access, 3 HMI access, 4 no access. */
  level: number;
  /** True when the PLC took the password; false when it wanted none (full access without it). */
  legitimated: boolean;
  /** The form used, when one was. */
  form?: LegitimationForm;
}

const LEVEL_NAMES: Record<number, string> = {
  [AccessLevel.None]: 'no protection',
  [AccessLevel.FullAccess]: 'full access',
  [AccessLevel.ReadAccess]: 'read access',
  [AccessLevel.HmiAccess]: 'HMI access',
  [AccessLevel.NoAccess]: 'no access',
};

/** "protection level 2 (read access)". */
function levelName(level: number): string {
  return `protection level ${level}${LEVEL_NAMES[level] ? ` (${LEVEL_NAMES[level]})` : ''}`;
}

/** Where the password can be given, for messages. */
const PASSWORD_WAYS =
  "connect(url, { password }), PLCWIRE_PASSWORD or --password-file FILE for the CLI, the connection node's password in Node-RED";

/** The legacy answer: SHA-1 of the password XOR the challenge's first 20 bytes (legitimation.py build_legacy_response). */
export function legacyAnswer(password: string, challenge: Buffer): Buffer {
  const hash = createHash('sha1').update(password, 'utf8').digest();
  const n = Math.min(hash.length, challenge.length);
  const out = Buffer.alloc(n);
  for (let i = 0; i < n; i++) out[i] = hash[i]! ^ challenge[i]!;
  return out;
}

/**
 * The new answer: the credentials (type 1, no user, the password's SHA-1) in
 * AES-256-CBC with PKCS#7 padding, key SHA-256 of the exporter secret, IV
 * the challenge's first 16 bytes (legitimation.py build_new_response with an
 * empty username).
 */
export function newAnswer(password: string, challenge: Buffer, exporterSecret: Buffer): Buffer {
  const key = createHash('sha256').update(exporterSecret).digest();
  const plain = encodeCredentials({
    type: LegitimationType.Legacy,
    username: Buffer.alloc(0),
    password: createHash('sha1').update(password, 'utf8').digest(),
  });
  const cipher = createCipheriv('aes-256-cbc', key, challenge.subarray(0, 16));
  return Buffer.concat([cipher.update(plain), cipher.final()]);
}

export interface LegitimateOptions {
  /** For messages: "s7plus://10.0.0.2:102". */
  name: string;
  password: string;
  /** The ServerSessionVersion of the CreateObject answer (its device string tells the form). */
  version: PValue | undefined;
  /** The TLS socket of the session; undefined in plain text (tls=false). */
  tls: TLSSocket | undefined;
  signal: AbortSignal;
}

/** Levels read per session: a refused write asks once. */
const levels = new WeakMap<S7PlusSession, Promise<number | undefined>>();

/**
 * Gives the password on `session` (the handshake's "password" step).
 * ACCESS_DENIED for a wrong password, NOT_SUPPORTED when the PLC or the URL
 * offers no way to give it; neither message holds the password.
 */
export async function legitimate(session: S7PlusSession, o: LegitimateOptions): Promise<Protection> {
  const refuse = (why: string) => new PlcError('NOT_SUPPORTED', `${o.name}: the password cannot be given: ${why}`);
  let before: number;
  try {
    before = await protectionLevel(session, o.signal);
  } catch (err) {
    if (err instanceof PlcError && err.code !== 'PROTOCOL_ERROR') throw err;
    throw refuse(`the PLC reports no protection level, so a password can be neither given nor checked (${(err as Error).message})`);
  }
  if (before <= AccessLevel.FullAccess) {
    // The PLC wants no password: the session has every right a password could give.
    levels.set(session, Promise.resolve(before));
    return { level: before, legitimated: false };
  }
  if (!o.tls)
    throw refuse('legitimation needs TLS, and tls=false is plain text (drop tls=false: the PLC then needs secure PG/HMI communication)');
  const paom = paomString(o.version);
  const form = paom === undefined ? undefined : legitimationForm(paom);
  if (!form)
    throw refuse(
      `the PLC's firmware (${paom === undefined ? 'it names none' : JSON.stringify(paom)}) takes no form of legitimation plcwire knows ` +
        '(the new one of S7-1500 from V3.1 and S7-1200 from V4.7, the legacy one of S7-1500 V2.9 to V3.0 and S7-1200 V4.3 to V4.6)',
    );
  const challenge = challengeOf(await attribute(session, Ids.ServerSessionRequest, o.signal));
  let address: number;
  let value: PValue;
  if (form === 'legacy') {
    if (challenge.length !== 20) throw new ProtocolError(`${o.name} gave a legacy challenge of ${challenge.length} bytes (20 expected)`);
    address = Ids.ServerSessionResponse;
    value = legacyAnswerValue(legacyAnswer(o.password, challenge));
  } else {
    if (challenge.length < 16) throw new ProtocolError(`${o.name} gave a challenge of ${challenge.length} bytes (at least 16 expected)`);
    address = Ids.Legitimate;
    value = credentialsBlobValue(newAnswer(o.password, challenge, exporterSecret(o.tls)));
  }
  const answer = await session.request(legitimateAsk(session.sessionId, address, value), { signal: o.signal });
  const wrong = (detail: string, plcCode?: number) =>
    new PlcError('ACCESS_DENIED', `${o.name} refused the password (wrong password: ${detail})`, {
      ...(plcCode === undefined ? {} : { plcCode }),
    });
  if (setVariableRefused(answer.returnValue)) {
    throw wrong(
      `the answer was refused with 0x${answer.returnValue.toString(16)}, the session keeps ${levelName(before)}`,
      Number(answer.returnValue & 0xffffn),
    );
  }
  const after = await protectionLevel(session, o.signal);
  levels.set(session, Promise.resolve(after));
  if (after >= before) throw wrong(`the session keeps ${levelName(after)}`);
  return { level: after, legitimated: true, form };
}

/**
 * The TLS exporter secret of the session (RFC 5705, RFC 8446 7.5), with an
 * empty context as the simulator's: under TLS 1.3, what s7commplus derives
 * (connection.py _derive_oms_secret), an empty and an absent context are the same.
 */
function exporterSecret(socket: TLSSocket): Buffer {
  try {
    return socket.exportKeyingMaterial(OMS_EXPORTER_LENGTH, OMS_EXPORTER_LABEL, Buffer.alloc(0));
  } catch (err) {
    throw new PlcError('NOT_SUPPORTED', `the TLS session gives no exporter secret for the new legitimation (${(err as Error).message})`);
  }
}

/** GetVarSubStreamed of one attribute of the session object: its value (ProtocolError for a refusal). */
async function attribute(session: S7PlusSession, address: number, signal: AbortSignal | undefined): Promise<PValue | undefined> {
  const res = await session.request(sessionAttributeAsk(session.sessionId, address), { signal });
  if (res.returnValue !== 0n)
    throw new ProtocolError(`S7CommPlus: the PLC refused the read of session attribute ${address} (0x${res.returnValue.toString(16)})`, {
      plcCode: Number(res.returnValue & 0xffffn),
    });
  return res.value;
}

/** The session's protection level (EffectiveProtectionLevel, 1842). */
async function protectionLevel(session: S7PlusSession, signal?: AbortSignal): Promise<number> {
  return protectionLevelOf(await attribute(session, Ids.EffectiveProtectionLevel, signal));
}

/** The level of `session`, read once; undefined when the PLC does not tell it (never throws). */
function knownLevel(session: S7PlusSession, signal?: AbortSignal): Promise<number | undefined> {
  let level = levels.get(session);
  if (!level) {
    level = protectionLevel(session, signal).catch(() => undefined);
    levels.set(session, level);
  }
  return level;
}

/**
 * A write the PLC refused on a session without a password: when the session
 * has less than full access, each refusal says so and how to give the
 * password (ACCESS_DENIED), instead of the PLC's bare item error.
 */
export async function readOnlyRefusals(
  session: S7PlusSession,
  name: string,
  items: readonly { tag: Tag }[],
  results: TagResult<void>[],
  signal?: AbortSignal,
): Promise<TagResult<void>[]> {
  // The PLC's own refusals of an item (not a value we could not encode, not a lost link).
  const refused = (r: TagResult<void>) => !r.ok && (r.error.code === 'PLC_ERROR' || r.error.code === 'OBJECT_DOES_NOT_EXIST');
  if (!results.some(refused) || !session.alive) return results;
  const level = await knownLevel(session, signal);
  if (level === undefined || level <= AccessLevel.FullAccess) return results;
  return results.map((r, i) => {
    if (r.ok || !refused(r)) return r;
    const tag = items[i]!.tag.address;
    const message =
      `${tag}: the PLC refused the write: ${name} gives this connection read access only without its password ` +
      `(${levelName(level)}); give the PLC's password: ${PASSWORD_WAYS}`;
    const plcCode = r.error.plcCode;
    return {
      ok: false,
      error: new PlcError('ACCESS_DENIED', message, { tag, cause: r.error, ...(plcCode === undefined ? {} : { plcCode }) }),
    };
  });
}
