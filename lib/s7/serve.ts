/** `plcwire serve s7`: the S7 simulator from the command line (lib/sim/serve.ts). */
import { hostPart } from '../link/url-params';
import type { MemoryLayout } from '../sim/memory';
import { servedBlocks, type Served, type ServeFlags } from '../sim/serve';
import { S7Server, refusalLine, type S7Profile, type S7RefusedEvent } from './server';
import { reloadOnChange, servePlus } from '../s7plus/server/serve';

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

export async function serveS7(flags: ServeFlags): Promise<Served> {
  const { host, say } = flags;
  const profile = (flags.string('profile') ?? 's7-1500').toLowerCase() as S7Profile;
  if (!PROFILES.includes(profile)) throw flags.usage(`--profile must be one of ${PROFILES.join(', ')}`);
  // Without --layout the profile's own memory (DB1 only for s7-200 and logo).
  const layout = loadLayout(flags, flags.string('layout'));
  // An S7-1200/1500 serves S7CommPlus on the same port, its blocks (optimized ones too) from --source.
  const s7plus = await servePlus(flags, profile);
  // --source: the data blocks of DB sources, at their declared lengths with their start values.
  const symbols = s7plus ? s7plus.model.table : flags.source();
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
  });
  // No connection is closed without a line saying which frame and why.
  server.on('refused', (e: S7RefusedEvent) => say(refusalLine(e)));
  const port = await flags.listen(() => server.listen(), 'port');
  say(`S7 simulator (${profile}) listening on ${host}:${port}${maxItems !== undefined ? `, at most ${maxItems} items per job` : ''}`);
  const url = `s7://${hostPart(host)}:${port}?${REACH[profile].query}`;
  // What PUT/GET serves is told from the sources' own table, in which an optimized block has no length.
  const shown = s7plus ? (flags.source() ?? symbols) : symbols;
  if (shown) for (const line of servedBlocks(shown)) say(line);
  say(`try: plcwire read "${url}" ${shown ? flags.tryByName(shown) : REACH[profile].addresses}`);
  if (s7plus?.fingerprint) {
    const protectedNote = !s7plus.protected ? '' : ', protected: writes need the password';
    say(`S7CommPlus over TLS on the same port, certificate SHA-256 ${s7plus.fingerprint}${protectedNote}`);
    say(`  s7plus://${hostPart(host)}:${port}?fingerprint=${s7plus.fingerprint}`);
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
