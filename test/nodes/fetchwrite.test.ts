import { describeProtocol } from './flows';
import { fetchWriteSim } from './sims';

describeProtocol('FETCH/WRITE', fetchWriteSim);
