/**
 * S7comm codec: pure functions over Buffers (no sockets). Encoders build one
 * whole frame (TPKT + COTP + S7) in one Buffer; decoders take one whole TPKT
 * frame and throw only ProtocolError on malformed, truncated or hostile input.
 * Constants and error words live in ../constants.
 */
export { checkTpkt, tpktFrame, assertTpkt } from '../../iso/tpkt';
export {
  decodeCotp,
  encodeConnectionConfirm,
  encodeConnectionRequest,
  encodeCotpError,
  encodeDisconnectRequest,
  type CotpConnection,
  type CotpMessage,
  type CotpParamOrder,
} from '../../iso/cotp';
export {
  dataLengthBytes,
  dataLengthField,
  dataPartLength,
  encodeErrorAck,
  encodeReadRequest,
  encodeReadResponse,
  encodeSetupAck,
  encodeSetupCommunication,
  encodeWriteRequest,
  encodeWriteResponse,
  readRequestPduSize,
  type ReadResponseItem,
  type S7Item,
  type S7Message,
  type S7WriteItem,
  type SetupParams,
} from './pdu';
export { decodeS7, s7AnswerRef, scanReadAck, type ReadItemTable } from './pdu-decode';
import type { S7Item, S7WriteItem } from './pdu';
/**
 * @deprecated The item of a Read Var job is `S7Item`; this second name stays
 * only because `s7.ReadItem` was public (lib/index.ts exports this module as `s7`).
 */
export type ReadItem = S7Item;
/**
 * @deprecated The item of a Write Var job is `S7WriteItem`; this second name
 * stays only because `s7.WriteItem` was public.
 */
export type WriteItem = S7WriteItem;
export {
  decodePassword,
  decodeUserdata,
  decodeUserdataParts,
  encodePassword,
  encodeUserdata,
  encodeUserdataNext,
  encodeUserdataRequest,
  encodeUserdataResponse,
  USERDATA_OVERHEAD,
  type UserdataAnswer,
  type UserdataParams,
  type UserdataPdu,
} from './userdata';
export {
  COLD_START_ARG,
  decodeControl,
  encodeControlAck,
  encodeEndUpload,
  encodePlcStart,
  encodePlcStop,
  encodeStartUpload,
  encodeStartUploadAck,
  encodeUpload,
  encodeUploadAck,
  isControlJob,
  type ControlMessage,
} from './control';
