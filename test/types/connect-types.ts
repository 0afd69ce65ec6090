/**
 * Compiled with the tests (tsconfig includes test/**), never run: connect()
 * and createClient() are typed by their URL's scheme. A line marked
 * @ts-expect-error must not compile; if it did, the build fails.
 */
import { connect, createClient, FetchWriteClient, FreeportClient, parseUrl, S7Client, type AnyClient } from '../../lib';

export async function typedByScheme(): Promise<void> {
  // An s7:// URL: the S7 client, its services callable without a cast.
  const plc = await connect('s7://192.168.0.1?rack=0&slot=1');
  const s7: S7Client = plc;
  const state: string | undefined = (await plc.info()).state;
  await plc.readSzl(0x0011);
  const fw: FetchWriteClient = await connect('fetchwrite://10.0.0.5?fetchPort=2000&writePort=2001');
  const serial: FreeportClient = await connect('freeport:///dev/ttyUSB0?baud=9600');
  const tcp: FreeportClient = createClient('freeport+tcp://10.0.0.7:4001');
  const unstarted: S7Client = createClient('s7://h');
  // A parsed endpoint is typed by its protocol too… when TypeScript knows it; parseUrl() gives any of them.
  const any: AnyClient = await connect(parseUrl(process.argv[2] ?? 's7://h'));
  // A string whose scheme is not known when compiling: any client, with what every client has.
  const url: string = process.argv[2] ?? 's7://h';
  const some = await connect(url);
  await some.read(['DB1.DBW0']);
  // @ts-expect-error -- a URL only known at run time may be FETCH/WRITE or freeport: no info() without narrowing.
  await some.info();
  // @ts-expect-error -- FETCH/WRITE has no S7 services.
  await fw.info();
  // @ts-expect-error -- an S7 client is not a FETCH/WRITE client.
  const wrong: FetchWriteClient = await connect('s7://h');
  if (some instanceof S7Client) await some.info();
  void [s7, state, serial, tcp, unstarted, any, wrong];
}
