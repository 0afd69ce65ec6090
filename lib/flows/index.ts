/** What flows (Node-RED or plain Node apps) do with tags beside reading and writing them. */
export { tagTable, tagsOfMessage } from './tag-list';
export { errorInfo, outcomes, tagFailure, type TagErrorInfo, type TagOutcome, type TagFailure } from './outcome';
export { valueChanged, ChangeFilter } from './change-filter';
export { PolledTable } from './polled-table';
export { realsForPeople } from '../symbols/reals';
export { writeRequest, type WriteRequest } from './write-request';
export {
  LifeSignWatch,
  nextLifeSign,
  LIFE_SIGN_COUNTER_MAX,
  type LifeSignMode,
  type LifeSignEvent,
  type LifeSignState,
  type LifeSignReport,
} from './life-sign';
