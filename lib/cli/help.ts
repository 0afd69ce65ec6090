/**
 * `plcwire <command> --help` (or `-h`, or `plcwire help <command>`): the
 * command's usage, what its options do, and an example to copy. The global
 * usage (main.ts) lists every command.
 */

const URL_NOTE = `url: s7://host?rack=0&slot=1, fetchwrite://host?fetchPort=2000&writePort=2001, freeport:///dev/ttyUSB0?baud=9600,
  s7plus://host?fingerprint=<SHA-256 of the PLC's certificate> (S7-1200/1500 over TLS; or ca=FILE, insecure=true on the bench)`;
const PASSWORD_OPTION = `  --password-file F  s7plus://: the PLC's password is the first line of F (else PLCWIRE_PASSWORD); never in the URL`;
const SYMBOL_OPTIONS = `  --symbols file     DB/UDT sources or a symbol table that declare the names (repeatable)
  --db NAME=N        the number of a TIA data block, which its source does not carry (repeatable)
  --strict-symbols   refuse names in a DB whose length in the PLC differs from the sources'`;

const HELP: Readonly<Record<string, string>> = {
  read: `usage: plcwire read <url> <address|symbol>... [--symbols file]... [--db NAME=N]... [--strict-symbols] [--json] [--timeout ms]
Reads each tag once and prints "address = value" (REAL with the digits TIA shows).
${SYMBOL_OPTIONS}
  --json             one JSON object keyed by the tags as given (64-bit integers as exact digits)
  --timeout ms       how long to wait for the PLC
${PASSWORD_OPTION}
${URL_NOTE}
example:
  plcwire read "s7://192.168.0.1?rack=0&slot=1" DB1.DBW2:INT MW4 '"Plant".Level' --symbols Plant.db --db Plant=1`,
  write: `usage: plcwire write <url> <address|symbol>=<value>... [--symbols file]... [--db NAME=N]... [--strict-symbols] [--yes] [--json] [--timeout ms]
Writes each value, checked against its tag's type before anything is sent; prints "address = value ok".
values: true/false/1/0 for BOOL, decimal or 0x hex numbers, ISO 8601 dates, text as is,
  arrays as a JSON array or comma-separated, a STRUCT by name as JSON ('"Tank".Motor={"Speed":2.5}')
${SYMBOL_OPTIONS}
  --yes              write to a PLC that is not on this machine without asking (needed in scripts)
  --json             one JSON object: "ok" or the error per tag
  --timeout ms       how long to wait for the PLC
${PASSWORD_OPTION}
${URL_NOTE}
example:
  plcwire write "s7://192.168.0.1?rack=0&slot=1" DB1.DBW2:INT=42 '"Plant".MotorRun=true' --symbols Plant.db --db Plant=1 --yes`,
  watch: `usage: plcwire watch <url> <address|symbol>... [--symbols file]... [--db NAME=N]... [--strict-symbols] [--interval ms] [--cycle ms] [--json]
Polls until Ctrl-C (exit code 130) and prints a line per changed value, all values first; reconnects by itself.
On s7plus:// the PLC reports the changes (a subscription on a session of its own, subscribed again after a
reconnect), on s7:// to an S7-300/400 its cyclic data does (the cycle rounded to steps of 100 ms, 1 s or 10 s);
a tag that cannot be subscribed is polled, and stderr says which and why.
${SYMBOL_OPTIONS}
  --interval ms      time between polls (default 1000)
  --cycle ms         s7plus://, s7:// (S7-300/400): how often the PLC samples the subscribed tags (default 100)
  --json             one JSON object per line: { "time": ISO 8601, "values": { tag: value } }
${PASSWORD_OPTION}
${URL_NOTE}
example:
  plcwire watch "s7://192.168.0.1?rack=0&slot=1" '"Plant".Level' MW4 --symbols Plant.db --db Plant=1 --interval 500`,
  symbols: `usage: plcwire symbols <file>... [--db NAME=N]... [--json | --csv]
Prints what DB/UDT sources (.db, .udt, .awl) and symbol tables (.sdf, .asc, .seq, .xlsx, .csv) compile to:
name, address, type, byte and bit of every member; a source that does not compile as file:line:column.
  --db NAME=N        the number of a TIA data block, which its source does not carry (repeatable)
  --json             an array of { name, type, db, byte, bit, address }
  --csv              RFC 4180 with a header row
example:
  plcwire symbols Plant.db --db Plant=1`,
  browse: `usage: plcwire browse <s7plus-url> [--password-file FILE] [--json | --csv]
Asks an S7-1200/1500 for its own tags over S7CommPlus (data blocks, optimized ones too, and the PLC tag table) and
prints them as plcwire symbols prints compiled sources: name, address, type, byte and bit; a member of an
optimized block has no address, byte or bit: read and write it by name on the same s7plus:// URL.
  --json             an array of { name, type, db, byte, bit, address }
  --csv              RFC 4180 with a header row
${PASSWORD_OPTION}
example:
  plcwire browse "s7plus://192.168.0.1?fingerprint=<64 hex digits the simulator or TIA shows>" --json`,
  info: `usage: plcwire info <url> [--json]
Prints what the PLC's client can tell: over s7:// the CPU's identity, its state (RUN, STOP, ...), protection,
PDU size, parallel jobs and clock; over s7plus:// its order code and firmware (the device string of the
session: major.minor), its state, the protocol version and the certificate of the TLS session.
${PASSWORD_OPTION}
example:
  plcwire info "s7://192.168.0.1?rack=0&slot=1" --json`,
  szl: `usage: plcwire szl <url> <id> [index] [--json]
Reads one SZL list; ID and index in hex as the manuals write them (0x0011, 0011, W#16#0011).
example:
  plcwire szl "s7://192.168.0.1?rack=0&slot=1" 0x0424 --json`,
  diag: `usage: plcwire diag <url> [--max N] [--json]
Prints the diagnostic buffer, newest first.
  --max N            the N most recent entries
example:
  plcwire diag "s7://192.168.0.1?rack=0&slot=1" --max 10`,
  clock: `usage: plcwire clock <url> [--set now|<ISO time>] [--yes] [--json]
Prints the PLC's clock; --set sets it (the URL needs control=true, and --yes in scripts or for a remote PLC).
example:
  plcwire clock "s7://192.168.0.1?rack=0&slot=1&control=true" --set now --yes`,
  blocks: `usage: plcwire blocks <url> [TYPE [NUMBER]] [--json]
Without a type: the count per type; with a type (OB, FB, FC, DB, SDB, SFC, SFB) its numbers; with a number its
block info. S7-1200/1500 have no block functions over S7comm; over s7plus:// they list their data blocks
with names and access (standard or optimized; no counts of code blocks, no block info).
example:
  plcwire blocks "s7://192.168.0.10?rack=0&slot=2" DB 10 --json`,
  cpu: `usage: plcwire cpu <url> stop|start|cold-start [--yes] [--json]
Changes the CPU's mode and prints the state after. The URL needs control=true; --yes in scripts or for a
PLC that is not on this machine.
example:
  plcwire cpu "s7://192.168.0.10?rack=0&slot=2&control=true" stop --yes`,
  alarms: `usage: plcwire alarms <url> [--watch [--mode] [--diagnostics]] [--language L] [--json] [--timeout ms]
Prints the alarms active now (S7-300/400 over s7://: the alarm query; S7-1200/1500 over s7plus://: the active-alarm
list), one per line: id, source, state, acknowledgement, priority, when it came, its text and associated values.
With --watch it prints one line per event as the PLC sends it until Ctrl-C (exit code 130): coming, going and
acknowledged; after a link loss it reconnects, subscribes again and prints what came or went meanwhile.
  --watch            print events until Ctrl-C instead of the active alarms
  --mode             with --watch: also the CPU's mode changes (STOP, RUN, ...)
  --diagnostics      with --watch: also the diagnostic messages the CPU sends
  --language L       the language of the texts (en-US, de-DE, ...; default the PLC's first)
  --json             a JSON array of the active alarms; with --watch one JSON object per event and line
  --timeout ms       how long to wait for the PLC
${PASSWORD_OPTION}
${URL_NOTE}
examples:
  plcwire alarms "s7://192.168.0.10?rack=0&slot=2"
  plcwire alarms "s7plus://192.168.0.1?fingerprint=<64 hex digits>" --watch --json`,
  ack: `usage: plcwire ack <url> <alarm id> [--yes] [--json] [--timeout ms]
Acknowledges one alarm, by the id plcwire alarms prints (decimal, 16#hex or 0x hex), and prints "alarm <id>
acknowledged" once the PLC confirmed it. An operator's write: a URL with readOnly=true refuses it, and one with
allow= only when the list names ALARMS or ALARM<id> (exit code 4, nothing sent); --yes in scripts or for a PLC
that is not on this machine.
  --yes              acknowledge on a PLC that is not on this machine without asking
  --json             { "id": ..., "acknowledged": true }
  --timeout ms       how long to wait for the PLC
${PASSWORD_OPTION}
${URL_NOTE}
example:
  plcwire ack "s7://192.168.0.10?rack=0&slot=2&allow=ALARMS" 1001 --yes`,
  doctor: `usage: plcwire doctor <url> [address|name...] [--json] [--timeout ms]
Walks the connection step by step and stops at the first failure with the fix in words. Over s7plus://:
TCP, COTP, InitSSL, TLS (the PLC's certificate; refused, it prints the URL with the fingerprint= that pins it),
the session, the password, the identity, the browse, then each name or address with its value and type.
  --timeout ms       the deadline of the whole walk (default 20000)
${PASSWORD_OPTION}
examples:
  plcwire doctor "s7://192.168.0.1?rack=0&slot=1" DB1.DBW0
  plcwire doctor "s7plus://192.168.0.1" '"Recipe".Step'`,
  serve: `usage: plcwire serve s7 [--port 102] [--host 127.0.0.1] [--profile s7-1500|s7-1200|s7-300|s7-400|s7-200|logo]
                   [--layout file.json] [--max-items N] [--source Tank.db... --db Tank=1...]
                   [--tls-cert cert.pem --tls-key key.pem] [--password-file FILE] [--alarms alarms.json]
       plcwire serve fetchwrite [--fetch-port 2000] [--write-port 2001] [--port N] [--host 127.0.0.1] [--source file... --db NAME=N...]
       plcwire serve freeport (--path <device> [--baud 9600] | --tcp <port> [--host 127.0.0.1]) [--stations 5,6]
Runs a simulated PLC until Ctrl-C and prints a try: line with the URL that reaches it.
  --source file      serve the data blocks of these DB sources, at their declared lengths with their start values;
                     for s7-1200/1500 also a TIA tag table (.xlsx, .csv): its I/Q/M names over s7plus://. Editing a
                     --source file, or SIGHUP, loads the program again, as a download (clients browse again)
  --tls-cert file    s7-1200/1500: the certificate (PEM) S7CommPlus over TLS presents, instead of one made at start
  --tls-key file     s7-1200/1500: its private key (PEM); --tls-cert and --tls-key go together
  --password-file F  s7-1200/1500: protect the CPU with the password on the first line of F: a session without
                     it reads only
  --tls-dir DIR      s7-1200/1500: keep the certificate in DIR (cert.pem, key.pem with mode 0600), made on the first
                     start and the same after, so a pinned fingerprint= still holds; else made anew at every start
  --alarms file      the program's alarms (JSON, docs/alarms.md): each comes when its trigger bit goes TRUE and
                     goes when it goes FALSE; s7-300/400 ALARM_S/SQ/8 and NOTIFY, s7-1200/1500 Program_Alarms
example:
  plcwire serve s7 --port 10102 --profile s7-1200 --source Plant.db --db Plant=1`,
  sparkplug: `usage: plcwire sparkplug --broker mqtt://host:1883 [--broker ...] --group G --node E --device NAME=<url> [--device ...]
         [--symbols file --db NAME=N]... [--tags NAME:<tag>,...] [--writable NAME:<tag>,...] [--alarms NAME]...
         [--primary-host H] [--interval ms] [--state-dir DIR] [--buffer N] [--buffer-dir DIR]
         [--mqtt-user U [--mqtt-password-file F]] [--mqtt-ca ca.pem] [--mqtt-cert cert.pem --mqtt-key key.pem]
Runs a Sparkplug B 3.0 edge node until Ctrl-C (exit code 130; NDEATH is sent before it disconnects): each PLC
a device whose tags are its metrics, typed from the PLC's types, data by exception every interval.
  --broker url       mqtt://, mqtts://, ws:// or wss://; repeat for a list: the next one when a broker fails or
                     the primary host goes offline on it
  --group G          the Sparkplug group id; --node E: the edge node id (no "/", "+" or "#")
  --device NAME=url  a PLC as the Sparkplug device NAME (repeatable)
  --tags NAME:t,t    the device's tags (symbols or addresses), each a metric of that name (repeatable); without
                     it every tag of --symbols, or on s7plus:// every tag the PLC's browse lists
  --writable NAME:t  tags of the device a host may write with DCMD (the URL's readOnly/allow still apply);
                     NAME:Alarms/Acknowledge lets a host acknowledge the PLC's alarms (allow=ALARMS or ALARM<id>)
  --alarms NAME      the device's PLC's alarms as its metrics Alarms/Active (a DataSet, a row each), Alarms/Active
                     Count, Alarms/Unacknowledged Count, Alarms/Event (each event as JSON) and Alarms/Acknowledge
                     (repeatable; s7:// S7-300/400, s7plus:// S7-1200/1500)
${SYMBOL_OPTIONS}
  --primary-host H   births wait for this host's STATE online; its offline moves to the next --broker
  --interval ms      time between polls (default 1000)
  --state-dir DIR    keep bdSeq in DIR between runs (Sparkplug hosts expect it to go on, not start at 0)
  --buffer N         store-and-forward: most values kept while no session is up (default 10000; 0: none)
  --buffer-dir DIR   keep them on disk in DIR too, so a restarted edge node forwards what an earlier one kept
  --mqtt-user U      the broker's user; its password is the first line of --mqtt-password-file F, else
                     PLCWIRE_MQTT_PASSWORD (never in the URL or a flag)
  --mqtt-ca F        mqtts:// (wss://): the CA (PEM) that signed the broker's certificate, else the system's;
                     a certificate it did not sign is refused and nothing is sent
  --mqtt-cert F      with --mqtt-key F: a client certificate (PEM) for brokers that ask for one
${PASSWORD_OPTION}
${URL_NOTE}
example:
  plcwire sparkplug --broker mqtt://127.0.0.1:1883 --group Plant --node Edge1 \\
    --device Line1="s7://127.0.0.1:10102?rack=0&slot=1" --symbols Plant.db --db Plant=1 \\
    --tags Line1:'"Plant".Level','"Plant".MotorRun' --writable Line1:'"Plant".MotorRun' --state-dir ./state`,
  demo: `usage: plcwire demo [options]
Runs all three simulators with a running process (no Node-RED) until Ctrl-C and prints try: lines.
options:
  --tls-dir DIR        keep the S7-1200's certificate in DIR, made on the first run (default: the directory
                       npm start keeps it in), so a pinned fingerprint= holds at every run
  --port N             the S7-1200's port, S7comm and S7CommPlus (default 10102; 0: any free port)
  --fetch-port N       the FETCH/WRITE CP's ports (default 12000 and 12001)
  --write-port N
  --freeport-port N    the S7-200 freeport stations' TCP port (default 14001)
example:
  plcwire demo`,
};

/** The help of `command`, or undefined when there is no such command. */
export function commandHelp(command: string): string | undefined {
  return Object.prototype.hasOwnProperty.call(HELP, command) ? HELP[command] : undefined;
}
