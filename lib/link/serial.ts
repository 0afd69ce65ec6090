/**
 * Opening and closing a serial port, for the freeport master and for the
 * station bus simulator alike: the serialport settings from a line's
 * parameters, the open and its error, the watch on the device while the port
 * is open, the close that always resolves.
 */
import * as fs from 'node:fs';
import type { BindingInterface } from '@serialport/bindings-interface';
import { SerialPortStream } from '@serialport/stream';
import { SerialPort } from 'serialport';
import { ConnectionError, PlcError, toPlcError } from '../errors';

/** Parity of a serial line. */
export type Parity = 'none' | 'even' | 'odd';

/** A line's parameters, as a freeport endpoint gives them. */
interface SerialLine {
  path: string;
  baudRate: number;
  parity: Parity;
  dataBits: 7 | 8;
  stopBits: 1 | 2;
}

export interface SerialOpenOptions extends SerialLine {
  /** A serialport binding other than the platform's (tests: `@serialport/binding-mock`). */
  binding?: BindingInterface;
  signal?: AbortSignal;
  /** How often the device's path is checked while the port is open, ms; 0: never (default DEVICE_CHECK_MS). */
  deviceCheckMs?: number;
}

/** Default period of the device check: a vanished device is noticed within about this long. */
const DEVICE_CHECK_MS = 500;

/**
 * Opens the port. Rejects with a PlcError: CONNECT_FAILED naming the path, or
 * ABORTED (a port that opens after `signal` aborted is closed again). The
 * port's 'error' events are taken: a read or write failing on a vanished
 * device is followed by 'close', which is where the owner learns of it.
 *
 * While the port is open its path is checked (see watchDevice); when it no
 * longer names the device that was opened, the port is closed and its
 * 'close' event carries a CONNECTION_LOST error saying so.
 */
export function openSerial(options: SerialOpenOptions): Promise<SerialPortStream> {
  const { path, baudRate, parity, dataBits, stopBits, binding, signal } = options;
  const checkMs = options.deviceCheckMs ?? DEVICE_CHECK_MS;
  const settings = { path, baudRate, parity, dataBits, stopBits, autoOpen: false } as const;
  const port: SerialPortStream = binding ? new SerialPortStream({ ...settings, binding }) : new SerialPort(settings);
  port.on('error', () => {});
  return new Promise((resolve, reject) => {
    const onAbort = () => reject(toPlcError(signal!.reason, 'ABORTED'));
    if (signal?.aborted) return onAbort();
    signal?.addEventListener('abort', onAbort, { once: true });
    port.open((err) => {
      if (err) {
        signal?.removeEventListener('abort', onAbort);
        return reject(openError(path, err));
      }
      // Who it is, taken once open: the device the port holds is the one the path names now.
      fs.stat(path, (statError, opened) => {
        signal?.removeEventListener('abort', onAbort);
        if (signal?.aborted) return void port.close(() => {});
        if (!statError && checkMs > 0) watchDevice(port, path, opened, checkMs);
        resolve(port);
      });
    });
  });
}

/**
 * Checks every `ms` (an unref'd timer, stopped by 'close') that `path` still
 * names the device `opened`; when it is gone (a USB adapter pulled: its /dev
 * node and its /dev/serial links are removed) or names another device (a link
 * re-pointed as the adapter came back), closes the port with a
 * CONNECTION_LOST error as the 'close' event's argument.
 *
 * Why a watch: a tty that has hung up answers every read with 0 bytes and
 * @serialport/bindings-cpp reads again at once
 * (https://github.com/serialport/bindings-cpp/issues/162), so when the hangup
 * comes while a read is on its way (rather than waiting in the poll, which
 * reports it) the port sees neither an error nor a close and a core stays
 * busy reading. Closing the port ends that loop: the bindings stop at a closed
 * descriptor. A port whose path is no file when it opens (a mock binding's, a
 * Windows COM name) is not watched.
 */
function watchDevice(port: SerialPortStream, path: string, opened: fs.Stats, ms: number): void {
  let timer: NodeJS.Timeout | undefined;
  const next = () => {
    timer = setTimeout(check, ms);
    timer.unref();
  };
  const check = () =>
    fs.stat(path, (err, now) => {
      if (!port.isOpen) return;
      const why = goneBecause(err, now, opened);
      if (!why) return next();
      port.close(undefined, new ConnectionError('CONNECTION_LOST', `serial device ${path} ${why}`));
    });
  port.once('close', () => clearTimeout(timer));
  next();
}

/** Closes the port; resolves once it is released, at once when it is not open. Never rejects. */
export function closeSerial(port: SerialPortStream): Promise<void> {
  return new Promise((resolve) => {
    if (!port.isOpen) return resolve();
    port.close(() => resolve());
  });
}

/** Why `path` no longer names the device `opened`; undefined while it does, or when stat cannot tell (look again). */
function goneBecause(err: NodeJS.ErrnoException | null, now: fs.Stats, opened: fs.Stats): string | undefined {
  if (err) return err.code === 'ENOENT' || err.code === 'ENOTDIR' ? 'disappeared' : undefined;
  return now.rdev !== opened.rdev || now.ino !== opened.ino ? 'now names another device' : undefined;
}

function openError(path: string, err: Error): PlcError {
  return new ConnectionError('CONNECT_FAILED', `cannot open serial port ${path}: ${err.message}`, { cause: err });
}
