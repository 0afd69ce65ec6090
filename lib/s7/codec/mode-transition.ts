/**
 * The mode-transition indication an S7-300/400 CPU pushes to a connection
 * registered for MODE events (issue #33). It is not a userdata PDU of function
 * group 0: its parameter begins with its own service byte, 0x01, where the
 * CPU services' userdata has the head 00 01 12. Sources: Apache PLC4X's
 * s7.mspec (`S7ParameterModeTransition`: parameter type 0x01 of a ROSCTR 7
 * PDU, the current mode in the seventh byte), and Wireshark's s7comm
 * dissector (packet-s7comm.c: a parameter whose first byte is the service
 * `S7COMM_SERV_MODETRANS` is a "Mode transition indication", its mode in the
 * seventh byte; Wireshark 4.0 reads the same bytes as userdata of function
 * group 0 with the mode as subfunction). Parameter, 8 bytes:
 *
 *   01        service: mode transition
 *   00 10     (PLC4X: reserved 0x0010)
 *   04        length of the rest
 *   11        method
 *   00        type 0 (push), function group 0
 *   mm        the new mode: 00 STOP, 01 warm restart, 02 RUN, 03 hot restart,
 *             04 HOLD, 06 cold restart (Wireshark's mode names)
 *   00        sequence number
 *
 * and no data part.
 */
import { FRAME_OVERHEAD } from '../../iso/constants';
import { Rosctr, S7_JOB_HEADER, S7_PROTOCOL_ID } from '../constants';
import { s7Frame } from './pdu';

/** The parameter's first byte of a mode-transition indication. */
const MODE_TRANSITION_SERVICE = 0x01;

const PARAMS = 8;

/** The indication of the CPU's new mode (0 STOP, 2 RUN, …). */
export function encodeModeTransition(mode: number): Buffer {
  const frame = s7Frame(Rosctr.UserData, 0, PARAMS, 0);
  const o = FRAME_OVERHEAD + S7_JOB_HEADER;
  Buffer.of(MODE_TRANSITION_SERVICE, 0x00, 0x10, 0x04, 0x11, 0x00, mode & 0xff, 0x00).copy(frame, o);
  return frame;
}

/** The new mode of a whole frame that is a mode-transition indication, or undefined when it is not one. */
export function decodeModeTransition(frame: Buffer): number | undefined {
  const o = FRAME_OVERHEAD + S7_JOB_HEADER;
  if (frame.length < o + PARAMS) return undefined;
  if (frame[FRAME_OVERHEAD] !== S7_PROTOCOL_ID || frame[FRAME_OVERHEAD + 1] !== Rosctr.UserData) return undefined;
  if (frame[o] !== MODE_TRANSITION_SERVICE || frame.readUInt16BE(FRAME_OVERHEAD + 6) < PARAMS) return undefined;
  return frame[o + 6];
}
