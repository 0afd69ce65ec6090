import { describeProtocol } from './flows';
import { s7Sim } from './sims';

describeProtocol('S7comm (ISO-on-TCP)', s7Sim);
