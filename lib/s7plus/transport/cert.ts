/**
 * A self-signed (or CA-signed) X.509 v3 certificate made at start with
 * node:crypto alone, for the S7CommPlus simulator's TLS and for tests. Never a
 * private key shipped in the package: every process makes its own.
 *
 * The key is RSA 2048 by default. The cipher suites S7 PLCs accept in TLS 1.2
 * (see trust.ts: ECDHE-RSA-AES*-GCM and the RSA key-exchange suites AES*-GCM /
 * AES*-SHA256, as the s7commplus package (MIT), connection.py `_S7_CIPHERS`
 * offers them) all authenticate the server with an RSA key; an EC key would
 * leave a TLS 1.2 client with no suite in common. TLS 1.3 would take either.
 *
 * The DER is written by the small encoder below (ITU-T X.690), with the
 * layout of RFC 5280 §4.1 (TBSCertificate) and the extensions of §4.2.
 */
import * as crypto from 'node:crypto';
import * as net from 'node:net';
import { promisify } from 'node:util';
import { ValueError } from '../../errors';

const generateKeyPair = promisify(crypto.generateKeyPair);

// --- DER (X.690) ---------------------------------------------------------------

function tlv(tag: number, content: Buffer): Buffer {
  const n = content.length;
  let head: Buffer;
  if (n < 0x80) head = Buffer.from([tag, n]);
  else {
    const bytes: number[] = [];
    for (let v = n; v > 0; v = Math.floor(v / 256)) bytes.unshift(v & 0xff);
    head = Buffer.from([tag, 0x80 | bytes.length, ...bytes]);
  }
  return Buffer.concat([head, content]);
}

const seq = (...items: Buffer[]): Buffer => tlv(0x30, Buffer.concat(items));
const set = (...items: Buffer[]): Buffer => tlv(0x31, Buffer.concat(items));
const octets = (content: Buffer): Buffer => tlv(0x04, content);
const bitString = (content: Buffer): Buffer => tlv(0x03, Buffer.concat([Buffer.from([0]), content]));
const explicit = (n: number, inner: Buffer): Buffer => tlv(0xa0 | n, inner);
const NULL = Buffer.from([0x05, 0x00]);
const TRUE = Buffer.from([0x01, 0x01, 0xff]);

/** A non-negative INTEGER from big-endian magnitude bytes (leading zeros trimmed, a 0x00 added when the top bit is set). */
function integer(magnitude: Buffer): Buffer {
  let i = 0;
  while (i < magnitude.length - 1 && magnitude[i] === 0) i++;
  const trimmed = magnitude.subarray(i);
  return tlv(0x02, trimmed[0]! & 0x80 ? Buffer.concat([Buffer.from([0]), trimmed]) : trimmed);
}

function oid(dotted: string): Buffer {
  const parts = dotted.split('.').map(Number);
  const bytes: number[] = [parts[0]! * 40 + parts[1]!];
  for (const part of parts.slice(2)) {
    const chunk: number[] = [part & 0x7f];
    for (let v = Math.floor(part / 128); v > 0; v = Math.floor(v / 128)) chunk.unshift(0x80 | (v & 0x7f));
    bytes.push(...chunk);
  }
  return tlv(0x06, Buffer.from(bytes));
}

/** UTCTime for 1950..2049, GeneralizedTime otherwise (RFC 5280 §4.1.2.5). */
function time(date: Date): Buffer {
  const iso = date.toISOString(); // YYYY-MM-DDTHH:MM:SS.sssZ
  const digits = iso.slice(0, 19).replace(/[-T:]/g, '');
  const year = date.getUTCFullYear();
  if (year >= 1950 && year < 2050) return tlv(0x17, Buffer.from(`${digits.slice(2)}Z`, 'ascii'));
  return tlv(0x18, Buffer.from(`${digits}Z`, 'ascii'));
}

// --- X.509 (RFC 5280) ----------------------------------------------------------

const OID = {
  commonName: '2.5.4.3',
  organization: '2.5.4.10',
  rsaSha256: '1.2.840.113549.1.1.11',
  ecdsaSha256: '1.2.840.10045.4.3.2',
  subjectKeyId: '2.5.29.14',
  keyUsage: '2.5.29.15',
  subjectAltName: '2.5.29.17',
  basicConstraints: '2.5.29.19',
  authorityKeyId: '2.5.29.35',
  extKeyUsage: '2.5.29.37',
  serverAuth: '1.3.6.1.5.5.7.3.1',
  clientAuth: '1.3.6.1.5.5.7.3.2',
};

function name(commonName: string): Buffer {
  const utf8 = (text: string) => tlv(0x0c, Buffer.from(text, 'utf8'));
  return seq(set(seq(oid(OID.organization), utf8('plcwire'))), set(seq(oid(OID.commonName), utf8(commonName))));
}

function extension(id: string, critical: boolean, value: Buffer): Buffer {
  return seq(oid(id), ...(critical ? [TRUE] : []), octets(value));
}

/** GeneralNames: dNSName [2] for names, iPAddress [7] for IPv4/IPv6 literals. */
function altNames(hosts: readonly string[]): Buffer {
  return seq(
    ...hosts.map((host) => {
      const family = net.isIP(host);
      if (family === 4) return tlv(0x87, Buffer.from(host.split('.').map(Number)));
      if (family === 6) return tlv(0x87, ipv6Bytes(host));
      if (!/^[A-Za-z0-9.*-]+$/.test(host)) throw new ValueError('certificate host', `"${host}" is neither an IP address nor a DNS name`);
      return tlv(0x82, Buffer.from(host, 'ascii'));
    }),
  );
}

function ipv6Bytes(text: string): Buffer {
  const [head, tail] = text.includes('::') ? text.split('::') : [text, undefined];
  const words = (part: string | undefined) => (part ? part.split(':').map((w) => parseInt(w, 16)) : []);
  const front = words(head);
  const back = words(tail);
  const all = tail === undefined ? front : [...front, ...new Array<number>(8 - front.length - back.length).fill(0), ...back];
  const out = Buffer.alloc(16);
  all.forEach((w, i) => out.writeUInt16BE(w, i * 2));
  return out;
}

/** keyUsage bits, numbered as in RFC 5280 §4.2.1.3 (bit 0 = the top bit of the first byte). */
function keyUsage(bits: number[]): Buffer {
  let value = 0;
  for (const bit of bits) value |= 0x8000 >> bit;
  const bytes = value & 0xff ? Buffer.from([value >> 8, value & 0xff]) : Buffer.from([value >> 8]);
  const last = bytes[bytes.length - 1]!;
  let unused = 0;
  while (unused < 7 && !(last & (1 << unused))) unused++;
  return tlv(0x03, Buffer.concat([Buffer.from([unused]), bytes]));
}

const DIGITAL_SIGNATURE = 0;
const KEY_ENCIPHERMENT = 2; // the RSA key-exchange suites encrypt the premaster secret to this key
const KEY_CERT_SIGN = 5;
const CRL_SIGN = 6;

export interface CertificateOptions {
  /** Subject common name; default "plcwire simulator". */
  commonName?: string;
  /** DNS names and IP addresses for subjectAltName; default localhost, 127.0.0.1 and ::1. */
  hosts?: readonly string[];
  /** Default: one hour ago (a clock a little behind still accepts it). */
  notBefore?: Date;
  /** Default: ten years after notBefore. */
  notAfter?: Date;
  /** 'rsa' (2048 bits, the default: what S7 cipher suites need) or 'ec' (P-256). */
  keyType?: 'rsa' | 'ec';
  /** A CA certificate (basicConstraints CA, keyCertSign) instead of a server one. */
  ca?: boolean;
  /** Sign with this CA instead of self-signing. */
  issuer?: GeneratedCertificate;
}

export interface GeneratedCertificate {
  /** PEM "CERTIFICATE". */
  cert: string;
  /** PEM PKCS#8 private key. */
  key: string;
  der: Buffer;
  /** SHA-256 of `der`, 64 upper-case hex digits (the value of a `fingerprint=` URL parameter). */
  fingerprint: string;
  commonName: string;
}

/** SHA-256 of a DER certificate as 64 upper-case hex digits, no colons. */
export function fingerprint256(der: Buffer): string {
  return crypto.createHash('sha256').update(der).digest('hex').toUpperCase();
}

/** PEM text of a DER certificate. */
function pem(der: Buffer): string {
  const lines = der.toString('base64').match(/.{1,64}/g) ?? [];
  return `-----BEGIN CERTIFICATE-----\n${lines.join('\n')}\n-----END CERTIFICATE-----\n`;
}

function signatureAlgorithm(key: crypto.KeyObject): Buffer {
  if (key.asymmetricKeyType === 'rsa') return seq(oid(OID.rsaSha256), NULL);
  if (key.asymmetricKeyType === 'ec') return seq(oid(OID.ecdsaSha256));
  throw new ValueError('certificate key', `key type ${key.asymmetricKeyType} is not supported (rsa or ec)`);
}

/** Key identifier of RFC 5280 §4.2.1.2 method (1): SHA-1 of the subjectPublicKey bits. */
function keyId(spki: Buffer): Buffer {
  return crypto.createHash('sha1').update(publicKeyBits(spki)).digest();
}

/** The BIT STRING contents (after the unused-bits byte) of a SubjectPublicKeyInfo. */
function publicKeyBits(spki: Buffer): Buffer {
  // SEQUENCE { AlgorithmIdentifier, BIT STRING }: skip the outer header and the first element.
  const skip = (buf: Buffer, at: number): { start: number; end: number } => {
    const first = buf[at + 1]!;
    const lenBytes = first & 0x80 ? first & 0x7f : 0;
    let len = lenBytes ? 0 : first;
    for (let i = 0; i < lenBytes; i++) len = len * 256 + buf[at + 2 + i]!;
    const start = at + 2 + lenBytes;
    return { start, end: start + len };
  };
  const outer = skip(spki, 0);
  const algorithm = skip(spki, outer.start);
  const bits = skip(spki, algorithm.end);
  return spki.subarray(bits.start + 1, bits.end);
}

/**
 * A fresh key pair and a certificate for it, signed by itself or by
 * `issuer`. RSA key generation takes tens of milliseconds and runs off the
 * event loop.
 */
export async function generateCertificate(options: CertificateOptions = {}): Promise<GeneratedCertificate> {
  const commonName = options.commonName ?? 'plcwire simulator';
  const hosts = options.hosts ?? ['localhost', '127.0.0.1', '::1'];
  const notBefore = options.notBefore ?? new Date(Date.now() - 3600_000);
  const notAfter = options.notAfter ?? new Date(notBefore.getTime() + 10 * 365.25 * 86400_000);
  if (!(notAfter.getTime() > notBefore.getTime())) {
    throw new ValueError('certificate validity', `notAfter ${notAfter.toISOString()} is not after notBefore ${notBefore.toISOString()}`);
  }
  const pair =
    options.keyType === 'ec'
      ? await generateKeyPair('ec', { namedCurve: 'P-256' })
      : await generateKeyPair('rsa', { modulusLength: 2048, publicExponent: 0x10001 });
  const spki = pair.publicKey.export({ type: 'spki', format: 'der' });
  const issuer = options.issuer;
  const signingKey = issuer ? crypto.createPrivateKey(issuer.key) : pair.privateKey;
  const issuerName = name(issuer ? issuer.commonName : commonName);
  const issuerKeyId = issuer
    ? keyId(new crypto.X509Certificate(issuer.der).publicKey.export({ type: 'spki', format: 'der' }))
    : keyId(spki);
  const serial = crypto.randomBytes(16);
  serial[0] = (serial[0]! & 0x7f) | 0x01; // positive, and 16 bytes long (RFC 5280 §4.1.2.2: at most 20)
  const usage = options.ca ? [DIGITAL_SIGNATURE, KEY_CERT_SIGN, CRL_SIGN] : [DIGITAL_SIGNATURE, KEY_ENCIPHERMENT];
  const extensions = [
    extension(OID.basicConstraints, true, options.ca ? seq(TRUE) : seq()),
    extension(OID.keyUsage, true, keyUsage(usage)),
    ...(options.ca ? [] : [extension(OID.extKeyUsage, false, seq(oid(OID.serverAuth), oid(OID.clientAuth)))]),
    ...(hosts.length > 0 && !options.ca ? [extension(OID.subjectAltName, false, altNames(hosts))] : []),
    extension(OID.subjectKeyId, false, octets(keyId(spki))),
    extension(OID.authorityKeyId, false, seq(tlv(0x80, issuerKeyId))),
  ];
  const algorithm = signatureAlgorithm(signingKey);
  const tbs = seq(
    explicit(0, integer(Buffer.from([2]))), // v3
    integer(serial),
    algorithm,
    issuerName,
    seq(time(notBefore), time(notAfter)),
    name(commonName),
    spki,
    explicit(3, seq(...extensions)),
  );
  const signature = crypto.sign('sha256', tbs, signingKey);
  const der = seq(tbs, algorithm, bitString(signature));
  return {
    cert: pem(der),
    key: pair.privateKey.export({ type: 'pkcs8', format: 'pem' }).toString(),
    der,
    fingerprint: fingerprint256(der),
    commonName,
  };
}
