/**
 * The connection doctor of any URL it knows: an s7plus:// URL walks the
 * S7CommPlus handshake (lib/s7plus/doctor), anything else the S7 one
 * (lib/s7/doctor, whose url step refuses other protocols in words). Both
 * give the same report: steps with ok, detail and a hint.
 */
import { diagnose as diagnoseS7, type DoctorReport } from './s7/doctor';
import { diagnosePlus, type PlusDiagnoseOptions } from './s7plus/doctor';

export type { DoctorReport, DoctorStep } from './s7/doctor';

/** What diagnose() takes: the S7 doctor's options and, for s7plus:// only, the PLC's password (never shown in a report). */
export type DiagnoseOptions = PlusDiagnoseOptions;

/**
 * Diagnoses the connection to a PLC, step by step, up to the first failure.
 * Resolves the report; rejects only with ABORTED when `options.signal`
 * aborts. Nothing is written to the PLC.
 */
export function diagnose(url: string, addresses: readonly string[] = [], options: DiagnoseOptions = {}): Promise<DoctorReport> {
  if (/^\s*s7plus:/i.test(url)) return diagnosePlus(url, addresses, options);
  const { password: _password, ...s7 } = options;
  return diagnoseS7(url, addresses, s7);
}
