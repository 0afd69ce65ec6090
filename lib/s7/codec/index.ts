/**
 * S7comm codec: pure functions over Buffers (no sockets). Encoders build one
 * whole frame (TPKT + COTP + S7) in one Buffer; decoders take one whole TPKT
 * frame and throw only ProtocolError on malformed, truncated or hostile input.
 * Constants and error words live in ../constants.
 */
export { checkTpkt, tpktFrame, assertTpkt } from './tpkt';
export {
  decodeCotp,
  encodeConnectionConfirm,
  encodeConnectionRequest,
  encodeCotpError,
  encodeDisconnectRequest,
  type CotpConnection,
  type CotpMessage,
  type CotpParamOrder,
} from './cotp';
export {
  dataLengthBytes,
  dataLengthField,
  dataPartLength,
  decodeS7,
  encodeErrorAck,
  encodeReadRequest,
  encodeReadResponse,
  encodeSetupAck,
  encodeSetupCommunication,
  encodeWriteRequest,
  encodeWriteResponse,
  readRequestPduSize,
  s7AnswerRef,
  scanReadAck,
  type ReadItemTable,
  type ReadItem,
  type ReadResponseItem,
  type S7Item,
  type S7Message,
  type S7WriteItem,
  type SetupParams,
  type WriteItem,
} from './pdu';
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
