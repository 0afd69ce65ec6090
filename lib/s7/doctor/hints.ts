/**
 * What the connection doctor tells a user to change, per step and cause: the
 * hint of a failed (or passed with a warning) step. The step's detail (what
 * was seen) stays with the step; these say what to do about it.
 */
import { NETWORK_HINT } from '../../iso/hints';
import { usualAddressing, type Addressing } from './families';

/** Where a CPU's protection is set: TIA Portal for an S7-1200/1500, the hardware configuration or mode selector for the others. */
const protectionSetting = (modern: boolean): string =>
  modern
    ? 'TIA Portal → the CPU\'s Properties → Protection & Security → Access level ("Full access" for writes)'
    : "the CPU's protection settings in the hardware configuration, or the mode selector";

export const HINT = {
  ...NETWORK_HINT,
  url: 'Write the URL as s7://<host>[:port]?rack=0&slot=1 (README, "URLs").',
  congestion:
    'All connections of the CPU are in use: close other clients (HMI, SCADA, TIA Portal online, other scripts) or give the CPU more connection resources in its hardware configuration.',
  /** The rack/slot or TSAP the CPU was found to accept (or none), then the usual values of each family. */
  addressing: (found: Addressing | undefined): string =>
    `${
      found
        ? `The CPU accepts ${found.label}, which points to ${found.family}: use ?${found.query} in the URL. `
        : 'None of the usual rack/slot or TSAP values was accepted either. '
    }${usualAddressing()}`,
  setupSilent:
    'The CPU accepted the connection but does not talk S7: check that the rack/slot or TSAP names the CPU (not a CP or a module without S7 communication).',
  setupClosed: "The CPU accepted the connection but not the S7 session: check rack/slot or TSAP, and the CPU's connection resources.",
  setupRefused: "The CPU refuses the S7 session: check the PDU size asked for (the pdu URL parameter) and the CPU's connection settings.",
  inStop:
    'The CPU is in STOP: memory can be read and written, but the program does not run (values do not change). Look at the diagnostic buffer (plcwire diag) for why it stopped.',
  noIdentity: 'The handshake works but the S7 connection does not: run the doctor again; if it repeats, report it with this output.',
  writeProtected: (modern: boolean): string =>
    `To write, give the password on the connection (S7Client.setPassword) or lower the protection: ${protectionSetting(modern)}.`,
  readProtected: (modern: boolean): string =>
    `Give the password on the connection (S7Client.setPassword) or lower the protection: ${protectionSetting(modern)}.`,
  putGet:
    'Allow PUT/GET in the CPU: TIA Portal → the CPU\'s Properties → Protection & Security → Connection mechanisms → tick "Permit access with PUT/GET communication from remote partner", then download the hardware configuration.',
  password: 'The protection level forbids reads: give the password (S7Client.setPassword) or lower the protection.',
  /** A name of the sources in a block with optimized access: PUT/GET cannot reach it; `plusUrl` is the same PLC over S7CommPlus. */
  optimizedName: (plusUrl: string): string =>
    `Read this name over S7CommPlus (the PLC finds the member by name, which PUT/GET cannot), with the same sources: try plcwire doctor ${plusUrl} "<name>" ` +
    "(it shows the PLC's certificate and the fingerprint= that pins it). " +
    'Or switch the DB to standard access: TIA Portal → the DB\'s Properties → Attributes → untick "Optimized block access", compile and download, ' +
    'then export its source again (Generate source from blocks) and read it over s7:// with PUT/GET.',
  /** An absolute address in a DB that is probably optimized; `plusUrl` is the same PLC over S7CommPlus. */
  optimizedDb: (plusUrl: string): string =>
    `An optimized DB is read by name over S7CommPlus: try plcwire doctor ${plusUrl} (it shows the PLC's certificate and the fingerprint= that pins it), ` +
    `then plcwire browse with the pinned URL lists the DB's names. Or switch the DB to standard access: TIA Portal → the DB's Properties → Attributes → ` +
    'untick "Optimized block access", compile and download; the DB editor then shows each variable\'s absolute offset (the Offset column) to use in the address.',
} as const;
