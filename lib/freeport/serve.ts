/** `plcwire serve freeport`: freeport stations on a serial port or a TCP port (lib/sim/serve.ts). */
import { hostPart } from '../link/url-params';
import { type Served, type ServeFlags } from '../sim/serve';
import { FreeportBus } from './bus';
import { FREEPORT_BAUD_RATES } from './url';

export async function serveFreeport(flags: ServeFlags): Promise<Served> {
  const { host, say } = flags;
  if (flags.hasSource()) throw flags.usage('--source builds data blocks: serve s7 or serve fetchwrite');
  const stations = parseStations(flags, flags.string('stations') ?? '5');
  const bus = new FreeportBus({ stations });
  const path = flags.string('path');
  if (path !== undefined && flags.has('tcp')) throw flags.usage('give --path or --tcp, not both');
  if (path !== undefined) {
    const baudRate = flags.int('baud', 9600, 1, 1_000_000);
    if (!FREEPORT_BAUD_RATES.includes(baudRate)) throw flags.usage(`--baud must be one of ${FREEPORT_BAUD_RATES.join(', ')}`);
    await bus.attachSerial(path, { baudRate });
    say(`freeport stations ${stations.join(', ')} answering on ${path} at ${baudRate} baud`);
  } else if (flags.has('tcp')) {
    const port = await flags.listen(() => bus.listenTcp({ host, port: flags.int('tcp', 4001, 0, 65535) }), 'tcp');
    say(`freeport stations ${stations.join(', ')} answering on tcp ${host}:${port}`);
    say(`try: plcwire read "freeport+tcp://${hostPart(host)}:${port}" ST${stations[0]},DWORD0`);
  } else {
    throw flags.usage('serve freeport needs --path <serial device> or --tcp <port>');
  }
  return { close: () => bus.close() };
}

function parseStations(flags: ServeFlags, text: string): number[] {
  const stations = text.split(',').map((s) => s.trim());
  return stations.map((s) => {
    if (!/^\d+$/.test(s) || Number(s) > 255) throw flags.usage(`--stations: "${s}" is not a station address 0..255`);
    return Number(s);
  });
}
