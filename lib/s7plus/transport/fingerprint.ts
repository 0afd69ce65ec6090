/**
 * A certificate's SHA-256 fingerprint as people write it, in one normal form: 64 upper-case hex digits, the form
 * `fingerprint256()` (cert.ts) computes and every message and start-up line shows. TIA Portal, openssl and browsers
 * write it with colons or spaces and either case; those are ignored. The URL's `fingerprint=` (url.ts) and the trust
 * decision (trust.ts) both read it here.
 */

/** The hex digits of `text`, colons and white space removed, upper-cased. */
function digits(text: string): string {
  return text.replace(/[\s:]/g, '').toUpperCase();
}

/** `text` as 64 upper-case hex digits, or undefined when it is not a SHA-256 fingerprint. */
export function normalizeFingerprint(text: string): string | undefined {
  const hex = digits(text);
  return /^[0-9A-F]{64}$/.test(hex) ? hex : undefined;
}

/** A fingerprint's bytes as TIA Portal and openssl show them, two upper-case hex digits each ("AB", "CD", …: joined by colons). */
export function fingerprintBytes(fingerprint: string): string[] {
  return digits(fingerprint).match(/../g) ?? [];
}

/** Why `text` is not a SHA-256 fingerprint (a character that is not a hex digit, or how many digits it has). */
export function fingerprintProblem(text: string): string {
  const hex = digits(text);
  const bad = /[^0-9A-F]/.exec(hex);
  if (bad) return `"${bad[0]}" is not a hex digit`;
  return `it has ${hex.length} hex digits${hex.length === 40 ? ' (a SHA-1 fingerprint?)' : ''}`;
}
