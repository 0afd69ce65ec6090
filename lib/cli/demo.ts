/** `plcwire demo`: the three simulated PLCs with a running process, until Ctrl-C. */
import { DEMO_STATIONS, startPlant } from '../plant/plant';
import { DEMO_TAGS } from '../plant/process';
import { EXIT, untilInterrupted, type CliIo } from './io';

export async function runDemo(io: CliIo): Promise<number> {
  const plant = await startPlant();
  const say = (line: string) => io.stdout.write(`${line}\n`);
  say('plcwire demo plant running (simulated S7-1200, FETCH/WRITE CP and S7-200 freeport stations):');
  say(`  S7          ${plant.urls.s7}`);
  say(`  FETCH/WRITE ${plant.urls.fetchwrite}`);
  say(`  freeport    ${plant.urls.freeport}  (stations ${DEMO_STATIONS.level}: level REAL, ${DEMO_STATIONS.parts}: parts DINT)`);
  say('try:');
  say(`  npx plcwire watch "${plant.urls.s7}" ${DEMO_TAGS.level} ${DEMO_TAGS.speed} ${DEMO_TAGS.parts}`);
  say(`  npx plcwire write "${plant.urls.s7}" ${DEMO_TAGS.run}=true`);
  say(`  npx plcwire read "${plant.urls.freeport}" ST${DEMO_STATIONS.level},REAL0`);
  say('Ctrl-C stops.');
  await untilInterrupted(io);
  await plant.close();
  return EXIT.OK;
}
