/**
 * Opening and closing a serial port, for the freeport master and for the
 * station bus simulator alike: the serialport settings from a line's
 * parameters, the open and its error, the close that always resolves.
 */
import type { BindingInterface } from '@serialport/bindings-interface';
import { SerialPortStream } from '@serialport/stream';
import { SerialPort } from 'serialport';
import { ConnectionError, PlcError, toPlcError } from '../errors';
import type { Parity } from '../url';

/** A line's parameters, as a freeport endpoint gives them. */
export interface SerialLine {
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
}

/**
 * Opens the port. Rejects with a PlcError: CONNECT_FAILED naming the path, or
 * ABORTED (a port that opens after `signal` aborted is closed again). The
 * port's 'error' events are taken: a read or write failing on a vanished
 * device is followed by 'close', which is where the owner learns of it.
 */
export function openSerial(options: SerialOpenOptions): Promise<SerialPortStream> {
  const { path, baudRate, parity, dataBits, stopBits, binding, signal } = options;
  const settings = { path, baudRate, parity, dataBits, stopBits, autoOpen: false } as const;
  const port: SerialPortStream = binding ? new SerialPortStream({ ...settings, binding }) : new SerialPort(settings);
  port.on('error', () => {});
  return new Promise((resolve, reject) => {
    const onAbort = () => reject(toPlcError(signal!.reason, 'ABORTED'));
    if (signal?.aborted) return onAbort();
    signal?.addEventListener('abort', onAbort, { once: true });
    port.open((err) => {
      signal?.removeEventListener('abort', onAbort);
      if (err) return reject(openError(path, err));
      if (signal?.aborted) return void port.close(() => {});
      resolve(port);
    });
  });
}

/** Closes the port; resolves once it is released, at once when it is not open. Never rejects. */
export function closeSerial(port: SerialPortStream): Promise<void> {
  return new Promise((resolve) => {
    if (!port.isOpen) return resolve();
    port.close(() => resolve());
  });
}

function openError(path: string, err: Error): PlcError {
  return new ConnectionError('CONNECT_FAILED', `cannot open serial port ${path}: ${err.message}`, { cause: err });
}
