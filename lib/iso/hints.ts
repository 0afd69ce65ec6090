/**
 * What a connection doctor tells a user to change when TCP or the ISO
 * connect step (connect.ts) fails, before any protocol of its own: the hints
 * the doctors of both protocols over ISO-on-TCP share (lib/s7/doctor,
 * lib/s7plus/doctor add their own). Words only: no import, nothing run.
 */
export const NETWORK_HINT = {
  noDns: "Check this machine's DNS settings, or use the PLC's IP address in the URL.",
  unknownHost:
    "Check the spelling of the host name, or use the PLC's IP address in the URL (TIA Portal: the CPU's Properties → PROFINET interface → Ethernet addresses).",
  filtered: (port: number): string =>
    'The PLC is off or unplugged, in another subnet without a route, or a firewall drops port ' +
    `${port}. Check that this machine is in the PLC's subnet (e.g. 192.168.0.x/24 for 192.168.0.1), that the PLC answers ping, and any firewall between.`,
  refused: `Check that the address is the PLC's (not a PC's or an HMI's) and the port: S7 uses 102; a gateway or simulator may use another (add :port to the URL).`,
  noRoute: "Check the IP address, this machine's subnet and gateway, and the cable.",
  notIsoOnTcp:
    'This is probably not an S7 PLC (another device or service on that address and port), or a communication processor that hangs: check the address, and power-cycle the CP.',
  otherProtocol: 'Another protocol listens on this port: check the address and the port (S7 uses 102).',
} as const;
