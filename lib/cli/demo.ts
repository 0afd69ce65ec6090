/** `plcwire demo`: the three simulated PLCs with a running process, until Ctrl-C. */
import * as path from 'node:path';
import { DEMO_STATIONS, startPlant } from '../plant/plant';
import { DEMO_TAGS } from '../plant/process';
import { TANK_SYMBOLS } from '../plant/tank';
import { EXIT, untilInterrupted, type CliIo } from './io';

/** demo/Plant.db beside dist/ (in the repository and in the installed package alike). */
const PLANT_SOURCE_FILE = path.resolve(__dirname, '..', '..', '..', 'demo', 'Plant.db');

export async function runDemo(io: CliIo): Promise<number> {
  const plant = await startPlant();
  const say = (line: string) => io.stdout.write(`${line}\n`);
  say('plcwire demo plant running (simulated S7-1200 with S7CommPlus, FETCH/WRITE CP and S7-200 freeport stations):');
  say(`  S7          ${plant.urls.s7}`);
  say(`  S7CommPlus  ${plant.urls.s7plus}  (TLS, pinned by the certificate made at start; the optimized DB "Tank" by name)`);
  say(`  FETCH/WRITE ${plant.urls.fetchwrite}`);
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
  say('Ctrl-C stops.');
  await untilInterrupted(io);
  await plant.close();
  return EXIT.OK;
}
