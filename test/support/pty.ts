/**
 * A linked pair of pseudo-terminals, the software stand-in for two serial
 * ports joined by a null-modem cable: what is written to one end is read on
 * the other, both ends are real tty devices that the real serialport bindings
 * open by path.
 *
 * Each end is a pty whose master this process holds; a relay copies bytes
 * between the two masters (what socat's `pty,raw,echo=0` pair does, without
 * socat). The ptys come from openpty(3) in @lydell/node-pty's prebuilt native
 * module, which npm installs from the registry: no compiler, no system package.
 *
 * Line discipline: the serialport bindings put a tty in raw mode when they
 * open it (input, output and local flags cleared), as they do a USB adapter;
 * until an end is opened it has a pty's default cooked settings, like any
 * serial device nobody has configured yet. So open both ends before sending.
 * The relay runs in this process and libuv writes to a pty master blocking: an
 * end nobody reads holds up the relay once the kernel's ~64 KiB buffer is full,
 * far beyond what a test sends.
 */
import * as fs from 'node:fs';
import * as path from 'node:path';
import * as tty from 'node:tty';

interface NativePty {
  /** openpty(3): both descriptors non-blocking; `pty` is the slave's device path. */
  open(cols: number, rows: number): { master: number; slave: number; pty: string };
}

const BINARY_PACKAGE = `@lydell/node-pty-${process.platform}-${process.arch}`;

/** Why no pty pair can be made on this machine, or undefined when it can. */
export function ptyUnavailable(): string | undefined {
  if (process.platform === 'win32') return 'Windows has no pseudo-terminals for the serialport bindings to open';
  const shipped =
    (require('@lydell/node-pty/package.json') as { optionalDependencies?: Record<string, string> }).optionalDependencies ?? {};
  if (!(BINARY_PACKAGE in shipped)) return `@lydell/node-pty ships no prebuilt binary for ${process.platform}-${process.arch}`;
  return undefined;
}

let native: NativePty | undefined;
function loadNative(): NativePty {
  if (native) return native;
  try {
    native = require(`${BINARY_PACKAGE}/pty.node`) as NativePty;
  } catch (err) {
    throw new Error(
      `cannot load ${BINARY_PACKAGE}/pty.node (installed with @lydell/node-pty unless npm ran with --omit=optional): ${(err as Error).message}`,
      {
        cause: err,
      },
    );
  }
  return native;
}

export interface PtyPair {
  /** Symlink to one end's device (the serial master's port). */
  readonly master: string;
  /** Symlink to the other end's device (the stations' port). */
  readonly station: string;
  /** Closes both ptys, as when a USB adapter is pulled: whoever has an end open sees it vanish. */
  stop(): Promise<void>;
}

interface End {
  link: string;
  slave: number;
  stream: tty.ReadStream;
  closed: Promise<void>;
}

function openEnd(link: string): End {
  const { master, slave, pty } = loadNative().open(80, 24);
  fs.rmSync(link, { force: true });
  fs.symlinkSync(pty, link);
  // tty.ReadStream is a net.Socket on the master: it reads and writes.
  const stream = new tty.ReadStream(master);
  const closed = new Promise<void>((resolve) => stream.once('close', () => resolve()));
  return { link, slave, stream, closed };
}

/** Opens two linked ptys reachable as `dir/master` and `dir/station`. */
export async function openPtyPair(dir: string): Promise<PtyPair> {
  const a = openEnd(path.join(dir, 'master'));
  const b = openEnd(path.join(dir, 'station'));
  const errors: Error[] = [];
  for (const [from, to] of [
    [a, b],
    [b, a],
  ] as const) {
    from.stream.on('data', (chunk: Buffer) => to.stream.write(chunk));
    from.stream.on('error', (err) => errors.push(err));
  }
  let stopped: Promise<void> | undefined;
  const stop = () =>
    (stopped ??= (async () => {
      for (const end of [a, b]) end.stream.destroy(); // closes the master: the slave's readers see a hangup
      await Promise.all([a.closed, b.closed]);
      for (const end of [a, b]) {
        fs.closeSync(end.slave);
        fs.rmSync(end.link, { force: true });
      }
      // A relay error while running would have lost bytes: say so rather than let a test pass by luck.
      const unexpected = errors.filter((e) => (e as NodeJS.ErrnoException).code !== 'EIO');
      if (unexpected.length) throw new Error(`pty relay failed: ${unexpected.map((e) => e.message).join('; ')}`);
    })());
  a.stream.resume();
  b.stream.resume();
  return { master: a.link, station: b.link, stop };
}
