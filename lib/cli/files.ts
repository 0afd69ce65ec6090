/**
 * Files named on the command line (--symbols, --source, --layout, the files of
 * `plcwire symbols`): read whole, or a failure in a user's words that names
 * the file as given (`no such file: Plant.db`), never a raw errno code.
 */
import { readFileSync } from 'node:fs';
import { PlcError } from '../errors';

/** What went wrong reading `file`, as one would say it; the errno code otherwise. */
function problem(file: string, err: NodeJS.ErrnoException): string {
  switch (err.code) {
    case 'ENOENT':
      return `no such file: ${file}`;
    case 'EISDIR':
      return `${file} is a folder, not a file`;
    case 'EACCES':
    case 'EPERM':
      return `no permission to read ${file}`;
    case 'ENOTDIR':
      return `no such file: ${file} (a part of its path is a file, not a folder)`;
    default:
      return `cannot read ${file}: ${err.message}`;
  }
}

/**
 * The bytes of `file`. A file that cannot be read is bad input (INVALID_SOURCE,
 * exit code 2): nothing was sent to any PLC.
 */
export function readInputFile(file: string): Buffer {
  try {
    return readFileSync(file);
  } catch (err) {
    throw new PlcError('INVALID_SOURCE', problem(file, err as NodeJS.ErrnoException), { cause: err });
  }
}
