/** `plcwire serve fetchwrite`: the FETCH/WRITE simulator from the command line (lib/sim/serve.ts). */
import { hostPart } from '../link/url-params';
import { servedBlocks, type Served, type ServeFlags } from '../sim/serve';
import { FetchWriteServer } from './server';

export async function serveFetchWrite(flags: ServeFlags): Promise<Served> {
  const { host, say } = flags;
  const single = flags.has('port') ? flags.int('port', 0, 0, 65535) : undefined;
  const symbols = flags.source();
  const server = new FetchWriteServer({
    host,
    ...(single !== undefined
      ? { port: single }
      : { fetchPort: flags.int('fetch-port', 2000, 0, 65535), writePort: flags.int('write-port', 2001, 0, 65535) }),
    ...(symbols ? { symbols } : {}),
  });
  const ports = await flags.listen(() => server.listen(), 'port');
  const query =
    ports.fetchPort === ports.writePort ? `port=${ports.fetchPort}` : `fetchPort=${ports.fetchPort}&writePort=${ports.writePort}`;
  say(`FETCH/WRITE simulator listening on ${host}: fetch ${ports.fetchPort}, write ${ports.writePort}`);
  if (symbols) for (const line of servedBlocks(symbols)) say(line);
  const url = `fetchwrite://${hostPart(host)}?${query}`;
  say(`try: ${symbols ? flags.tryRead(url, symbols) : `plcwire read "${url}" DB1,INT0 MB0`}`);
  return { close: () => server.close() };
}
