import { describeProtocol } from './flows';
import { freeportSim } from './sims';

describeProtocol('S7-200 freeport (serial device server)', freeportSim);
