/** `plcwire demo`: the three simulated PLCs with a running process, until Ctrl-C. */
import * as path from 'node:path';
import { ValueError } from '../errors';
import { demoCertificateDir } from '../plant/certificate-dir';
import { DEMO_PORTS, DEMO_STATIONS, startPlant, type Plant } from '../plant/plant';
import { DEMO_TAGS } from '../plant/process';
import { TANK_SYMBOLS } from '../plant/tank';
import { intFlag, stringFlag, UsageError, type ParsedArgs } from './args';
import { EXIT, untilInterrupted, type CliIo } from './io';

/** demo/Plant.db beside dist/ (in the repository and in the installed package alike). */
const PLANT_SOURCE_FILE = path.resolve(__dirname, '..', '..', '..', 'demo', 'Plant.db');

/**
 * The plant on the ports the flags name (0: any free port), its S7-1200's certificate kept in --tls-dir, by default
 * the directory `npm start` keeps it in (demoCertificateDir()): a URL pinned once stays pinned.
 */
async function plantOf(args: ParsedArgs, tlsDir: string): Promise<Plant> {
  const port = (flag: string, fallback: number) => intFlag(args, flag, fallback, 0, 65535);
  const ports = {
    s7: port('port', DEMO_PORTS.s7),
    fetch: port('fetch-port', DEMO_PORTS.fetch),
    write: port('write-port', DEMO_PORTS.write),
    freeport: port('freeport-port', DEMO_PORTS.freeport),
  };
  try {
    return await startPlant({ ports, tlsDir });
  } catch (err) {
    // What is wrong with the directory, said with the flag that names it.
    if (err instanceof ValueError && err.tag === 'tlsDir')
      throw new UsageError(`--tls-dir: ${err.message.slice(err.message.indexOf(': ') + 2)}`);
    throw err;
  }
}

export async function runDemo(rest: readonly string[], args: ParsedArgs, io: CliIo): Promise<number> {
  if (rest.length > 0) throw new UsageError(`unexpected argument "${rest[0]}"`);
  const tlsDir = stringFlag(args, 'tls-dir') ?? demoCertificateDir();
  const plant = await plantOf(args, tlsDir);
  const say = (line: string) => io.stdout.write(`${line}\n`);
  say('plcwire demo plant running (simulated S7-1200 with S7CommPlus, FETCH/WRITE CP and S7-200 freeport stations):');
  say(`  S7          ${plant.urls.s7}`);
  say(`  S7CommPlus  ${plant.urls.s7plus}  (TLS; the optimized DB "Tank" by name)`);
  say(`              the certificate is kept in ${tlsDir}: the same fingerprint at every run`);
  say(`  FETCH/WRITE ${plant.urls.fetchwrite}`);
  say(`  S7-300      ${plant.urls.s7classic}  (classic CPU, same program: the tank's high level is an ALARM_SQ)`);
  say(`  freeport    ${plant.urls.freeport}  (stations ${DEMO_STATIONS.level}: level REAL, ${DEMO_STATIONS.parts}: parts DINT)`);
  say('try:');
  say(`  npx plcwire watch "${plant.urls.s7}" ${DEMO_TAGS.level} ${DEMO_TAGS.speed} ${DEMO_TAGS.parts}`);
  say(`  npx plcwire write "${plant.urls.s7}" ${DEMO_TAGS.run}=true`);
  // By name, from the plant's own DB source (shipped with the package: package.json "files").
  const source = JSON.stringify(PLANT_SOURCE_FILE);
  say(`  npx plcwire watch "${plant.urls.s7}" '"Plant".Level' '"Plant".MotorSpeed' --symbols ${source} --db Plant=1`);
  say(`  npx plcwire read "${plant.urls.freeport}" ST${DEMO_STATIONS.level},REAL0`);
  // The optimized DB: no source file, the names come from the PLC (browse), read and written by name over TLS.
  say(`  npx plcwire browse "${plant.urls.s7plus}"`);
  say(`  npx plcwire watch "${plant.urls.s7plus}" '${TANK_SYMBOLS.phase}' '${TANK_SYMBOLS.speed}' '${TANK_SYMBOLS.levels}'`);
  say(`  npx plcwire write "${plant.urls.s7plus}" '${TANK_SYMBOLS.setpoint}=45'`);
  // The tank's high level (85 %) as an alarm on both generations (issue #33).
  say(`  npx plcwire alarms "${plant.urls.s7classic}" --watch`);
  say(`  npx plcwire alarms "${plant.urls.s7plus}" --watch`);
  say('Ctrl-C stops.');
  await untilInterrupted(io);
  await plant.close();
  return EXIT.OK;
}
