/**
 * How `plcwire sparkplug` reaches a plant's broker: a user (--mqtt-user), its
 * password (the first line of --mqtt-password-file, else PLCWIRE_MQTT_PASSWORD;
 * never a flag or in the URL, where logs and process lists would show it), and
 * for mqtts:// / wss:// brokers the CA that signed them (--mqtt-ca) and a client
 * certificate (--mqtt-cert with --mqtt-key). Each mistake is a UsageError
 * (exit code 2) that names the option and never the password.
 */
import type * as mqtt from 'mqtt';
import { brokerName } from '../sparkplug/brokers';
import { stringFlag, UsageError, type ParsedArgs } from './args';
import { readInputFile } from './files';
import { secretFromFile } from './s7plus';

export const MQTT_FLAGS = ['mqtt-user', 'mqtt-password-file', 'mqtt-ca', 'mqtt-cert', 'mqtt-key'];

/** The environment variable the broker password may come from. */
const MQTT_PASSWORD_ENV = 'PLCWIRE_MQTT_PASSWORD';

const TLS_SCHEMES = ['mqtts:', 'wss:'];

/** A broker URL of --broker: mqtt://, mqtts://, ws:// or wss://, without a user or password in it. */
export function brokerUrl(raw: string): string {
  let url: URL;
  try {
    url = new URL(raw);
  } catch {
    throw new UsageError(`--broker ${JSON.stringify(brokerName(raw))} is not a URL: give mqtt://host[:1883] or mqtts://host[:8883]`);
  }
  if (!['mqtt:', 'mqtts:', 'ws:', 'wss:'].includes(url.protocol))
    throw new UsageError(`--broker ${JSON.stringify(brokerName(raw))}: the scheme must be mqtt://, mqtts://, ws:// or wss://`);
  if (url.username !== '' || url.password !== '')
    throw new UsageError(
      `--broker ${JSON.stringify(brokerName(raw))}: no user or password in the URL (logs and process lists show it); give --mqtt-user and the password in ${MQTT_PASSWORD_ENV} or --mqtt-password-file`,
    );
  return raw;
}

/** The MQTT.js options of the login and TLS flags, checked against the brokers (all TLS or all plain). */
export function mqttOptions(args: ParsedArgs, brokers: readonly string[], env: NodeJS.ProcessEnv = process.env): mqtt.IClientOptions {
  const tls = brokers.map((b) => TLS_SCHEMES.includes(new URL(b).protocol));
  if (tls.some(Boolean) && !tls.every(Boolean))
    throw new UsageError(
      '--broker: the brokers mix mqtts:// (wss://) and mqtt:// (ws://): moving to the next broker would fall back to plain text; give all of one kind',
    );
  const out: mqtt.IClientOptions = {};
  const user = flag(args, 'mqtt-user');
  const passwordFile = flag(args, 'mqtt-password-file');
  const password = passwordFile !== undefined ? secretFromFile('mqtt-password-file', passwordFile) : env[MQTT_PASSWORD_ENV] || undefined;
  if (password !== undefined && user === undefined)
    throw new UsageError(
      `${passwordFile !== undefined ? '--mqtt-password-file' : MQTT_PASSWORD_ENV} gives a password but no --mqtt-user: give the user too`,
    );
  if (user !== undefined) out.username = user;
  if (password !== undefined) out.password = password;
  const ca = flag(args, 'mqtt-ca');
  const cert = flag(args, 'mqtt-cert');
  const key = flag(args, 'mqtt-key');
  if ((ca ?? cert ?? key) !== undefined && !tls[0])
    throw new UsageError('--mqtt-ca, --mqtt-cert and --mqtt-key are for mqtts:// or wss:// brokers; the --broker list is plain text');
  if ((cert === undefined) !== (key === undefined))
    throw new UsageError('--mqtt-cert and --mqtt-key go together (the client certificate and its key)');
  if (ca !== undefined) out.ca = pem('mqtt-ca', ca);
  if (cert !== undefined && key !== undefined) {
    out.cert = pem('mqtt-cert', cert);
    out.key = pem('mqtt-key', key);
  }
  return out;
}

function flag(args: ParsedArgs, name: string): string | undefined {
  const value = stringFlag(args, name);
  if (args.flags.has(name) && (value === undefined || value === '')) throw new UsageError(`--${name} needs a value`);
  return value;
}

/** A PEM file's bytes; one that cannot be read, or holds no PEM block, is a UsageError naming the option and the file. */
function pem(name: string, file: string): Buffer {
  let bytes: Buffer;
  try {
    bytes = readInputFile(file);
  } catch (err) {
    throw new UsageError(`--${name}: ${(err as Error).message}`);
  }
  if (!/-----BEGIN [A-Z0-9 ]+-----/.test(bytes.toString('latin1')))
    throw new UsageError(`--${name} ${file}: not a PEM file (no "-----BEGIN …-----" line)`);
  return bytes;
}
