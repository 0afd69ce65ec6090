/**
 * `plcwire serve s7`: a simulated S7 CPU from the command line (lib/sim/serve.ts). The S7 simulator (lib/s7/server)
 * serves PUT/GET; for an S7-1200 or S7-1500 this composes it with the S7CommPlus service (lib/s7plus/server) on the
 * same port and memory, as the CPU serves both (the COTP CR's called TSAP decides). It sits above both protocol
 * folders, so neither imports the other.
 */
import { hostPart } from '../link/url-params';
import type { MemoryLayout } from '../sim/memory';
import { servedBlocks, type Served, type ServeFlags } from '../sim/serve';
import { S7Server, refusalLine, type S7Profile, type S7RefusedEvent } from '../s7/server';
import { servePlus } from '../s7plus/server/serve';
import { reloadOnChange } from './reload';
import { parseAlarmDefinitions } from '../alarms/definitions';

const PROFILES: readonly S7Profile[] = ['s7-300', 's7-400', 's7-1200', 's7-1500', 's7-200', 'logo'];

/** The URL query that reaches each profile's CPU: rack/slot, or the TSAP pair a TSAP-addressed CPU accepts. */
const REACH: Readonly<Record<S7Profile, { query: string; addresses: string }>> = Object.freeze({
  's7-300': { query: 'rack=0&slot=2', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-400': { query: 'rack=0&slot=2', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-1200': { query: 'rack=0&slot=1', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-1500': { query: 'rack=0&slot=1', addresses: 'DB1,INT0 MW10 M0.1' },
  's7-200': { query: 'localTsap=1000&remoteTsap=1001', addresses: 'VW0 VB10 M0.1' },
  logo: { query: 'localTsap=0100&remoteTsap=0200', addresses: 'VW0 V1024.0' },
});

/** The profiles whose CPUs speak S7CommPlus beside PUT/GET. */
const PLUS_PROFILES: ReadonlySet<S7Profile> = new Set(['s7-1200', 's7-1500']);

/** The S7CommPlus flags on a CPU without S7CommPlus: a usage error. */
function refusePlusFlags(flags: ServeFlags, profile: S7Profile): undefined {
  if (['tls-cert', 'tls-key', 'tls-dir', 'password-file'].some((flag) => flags.has(flag)))
    throw flags.usage(`--tls-cert, --tls-key, --tls-dir and --password-file are for an S7-1200 or S7-1500 (S7CommPlus), not ${profile}`);
  return undefined;
}

export async function serveS7(flags: ServeFlags): Promise<Served> {
  const { host, say } = flags;
  const profile = (flags.string('profile') ?? 's7-1500').toLowerCase() as S7Profile;
  if (!PROFILES.includes(profile)) throw flags.usage(`--profile must be one of ${PROFILES.join(', ')}`);
  // Without --layout the profile's own memory (DB1 only for s7-200 and logo).
  const layout = loadLayout(flags, flags.string('layout'));
  // An S7-1200/1500 serves S7CommPlus on the same port, its blocks (optimized ones too) from --source.
  // --alarms: the program's alarm blocks; an S7-300/400 raises them over S7comm, an S7-1200/1500 as Program_Alarms over S7CommPlus.
  const alarmsFile = flags.string('alarms');
  const alarms = alarmsFile === undefined ? undefined : parseAlarmDefinitions(flags.readFile(alarmsFile).toString('utf8'), alarmsFile);
  const s7plus = PLUS_PROFILES.has(profile) ? await servePlus(flags, alarms) : refusePlusFlags(flags, profile);
  // --source: the data blocks of DB sources, at their declared lengths with their start values. With S7CommPlus they
  // are its program's (optimized ones too, laid out for the simulator's storage), which S7Server takes itself when
  // the program has data blocks; without --source the profile's (or --layout's) data blocks stay (issue #31).
  const symbols = s7plus ? undefined : flags.source();
  // --max-items: serve at most N items per job, as snap7's server (20) and the devices built on it.
  const maxItems = flags.has('max-items') ? flags.int('max-items', 20, 1, 255) : undefined;
  const server = new S7Server({
    host,
    port: flags.int('port', 102, 0, 65535),
    profile,
    ...(layout ? { layout } : {}),
    ...(symbols ? { symbols } : {}),
    ...(maxItems !== undefined ? { maxItems } : {}),
    ...(s7plus ? { s7plus } : {}),
    ...(alarms && !s7plus ? { alarms } : {}),
  });
  // No connection is closed without a line saying which frame and why.
  server.on('refused', (e: S7RefusedEvent) => say(refusalLine(e)));
  const port = await flags.listen(() => server.listen(), 'port');
  say(`S7 simulator (${profile}) listening on ${host}:${port}${maxItems !== undefined ? `, at most ${maxItems} items per job` : ''}`);
  if (alarms)
    say(
      `${alarms.length} alarm${alarms.length === 1 ? '' : 's'} from ${alarmsFile}: ${s7plus ? 'Program_Alarms over s7plus://' : 'ALARM_S/SQ/8, NOTIFY over s7://'}`,
    );
  const url = `s7://${hostPart(host)}:${port}?${REACH[profile].query}`;
  // What PUT/GET serves is told from the sources' own table, in which an optimized block has no length.
  const shown = s7plus ? flags.source() : symbols;
  if (shown) for (const line of servedBlocks(shown)) say(line);
  const plusUrl = s7plus?.fingerprint ? `s7plus://${hostPart(host)}:${port}?fingerprint=${s7plus.fingerprint}` : undefined;
  say(`try: ${shown ? flags.tryRead(url, shown, plusUrl) : `plcwire read "${url}" ${REACH[profile].addresses}`}`);
  if (s7plus?.fingerprint) {
    const protectedNote = !s7plus.protected ? '' : ', protected: writes need the password';
    say(`S7CommPlus over TLS on the same port, certificate SHA-256 ${s7plus.fingerprint}${protectedNote}`);
    say(`  ${plusUrl}`);
    const tlsDir = flags.string('tls-dir');
    if (tlsDir !== undefined) say(`  the certificate is kept in ${tlsDir}: the same fingerprint at every start`);
  }
  // A download: the program loaded again on SIGHUP or when a --source file changes.
  const stopWatching = s7plus && flags.hasSource() ? reloadOnChange(s7plus, server.memory, flags) : undefined;
  return {
    close: () => {
      stopWatching?.();
      return server.close();
    },
  };
}

function loadLayout(flags: ServeFlags, file: string | undefined): MemoryLayout | undefined {
  if (file === undefined) return undefined;
  const text = flags.readFile(file).toString('utf8');
  try {
    return JSON.parse(text) as MemoryLayout;
  } catch (err) {
    throw flags.usage(`--layout ${file} is not JSON: ${(err as Error).message}`);
  }
}
