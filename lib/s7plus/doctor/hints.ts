/**
 * What the S7CommPlus connection doctor (index.ts) tells a user to change,
 * per step and cause. The step's detail says what was seen; these say what
 * to do. Facts: docs/s7commplus.md (firmware, secure PG/HMI communication).
 */
const SECURE =
  'TIA Portal → the CPU\'s Properties → Protection & Security → Connection mechanisms / Certificate manager ("secure PG/HMI communication")';

export const PLUS_HINT = {
  url: 'Write the URL as s7plus://<host>[:102]?fingerprint=<SHA-256 of the PLC\'s certificate> (README, "Optimized blocks (S7CommPlus)").',
  refusedTsap:
    'The CPU does not take S7CommPlus connections on this port: an S7-300/400 (or an S7-1200/1500 behind a CP, or a gateway) speaks PUT/GET only: use s7:// with standard-access data blocks. ' +
    'On an S7-1200/1500, all of its connections may be in use: close other clients (HMI, TIA Portal online).',
  notPlusCpu: 'This CPU does not speak S7CommPlus (an S7-300/400, LOGO! or S7-200): use s7:// with standard-access data blocks.',
  /** A certificate nothing in the URL trusts: the URL that pins the one the PLC showed. */
  pin: (url: string): string =>
    `Check the fingerprint against the CPU's certificate (TIA Portal → the CPU's Properties → Protection & Security → Certificate manager, ` +
    `or the display of the CPU), then pin it: ${url}`,
  expired: `Renew the CPU's certificate in TIA Portal (${SECURE}) and download the hardware configuration; or check this machine's clock.`,
  notSignedByCa: "Give the CA of the TIA project that signed the CPU's certificate (ca=FILE), or pin the certificate: ",
  tlsRefused:
    `The PLC did not take the TLS handshake. A PLC without secure PG/HMI communication speaks plain S7CommPlus: tls=false reaches it (without encryption), ` +
    `or switch it on: ${SECURE}, firmware S7-1500 V2.9 / S7-1200 V4.5 or later.`,
  plainAsked: `The PLC wants TLS: drop tls=false (never a fallback to plain text), pin its certificate (fingerprint=), and keep ${SECURE} on.`,
  plainText: 'tls=false: nothing of this connection is encrypted or authenticated; use it only where the network is trusted.',
  session:
    'The handshake worked but the PLC did not open a session: check that the CPU has a free connection and its firmware (docs/s7commplus.md, "What the PLC needs"); run the doctor again, and report it with this output if it repeats.',
  insecure: (url: string): string => `insecure=true accepts any certificate: pin this one instead: ${url}`,
  password:
    "Check the password against the access level in TIA Portal (the CPU's Properties → Protection & Security → Access level), or lower the protection and download.",
  inStop:
    'The CPU is in STOP: memory can be read and written, but the program does not run (values do not change). Look at the diagnostic buffer in TIA Portal for why it stopped.',
  noTypes:
    'The PLC lists its data blocks but gives no type information for them: names cannot be read; read standard DBs by address (DB1.DBW0:INT).',
  name: 'Check the name against the PLC\'s tags (plcwire browse <url> lists them, as TIA writes them: "Tank".Motor.Speed).',
  address: 'Write the address as DB<n>.DBW<offset>:INT (standard-access DBs only), or read the member by its name.',
} as const;
