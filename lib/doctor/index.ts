/**
 * The connection doctor of any URL: the URL parsed here (a URL that does not
 * parse, or whose protocol has no doctor, is a failed `url` step), then the
 * steps of its driver's diagnose port (lib/drivers.ts: lib/s7/doctor for
 * s7://, lib/s7plus/doctor for s7plus://), walked by lib/doctor/walk.ts. Every
 * doctor gives the same report: steps with ok, detail and a hint.
 */
import { DRIVERS, driverOf, schemesOffering, type Endpoint } from '../drivers';
import type { DiagnosePort, DiagnoseOptions, DoctorReport, DoctorStep } from './types';
import { deadlineOf } from './walk';
import { formatUrl, parseUrl } from '../url';

export type { DiagnoseOptions, DoctorReport, DoctorStep } from './types';

/**
 * Diagnoses the connection to a PLC, step by step, up to the first failure.
 * Resolves the report; rejects only with ABORTED when `options.signal`
 * aborts. Nothing is written to the PLC.
 */
export async function diagnose(url: string, addresses: readonly string[] = [], options: DiagnoseOptions = {}): Promise<DoctorReport> {
  deadlineOf(options); // a bad timeout is refused before anything else, whatever the URL
  let endpoint: Endpoint;
  try {
    endpoint = parseUrl(url);
  } catch (err) {
    return urlFailed((err as Error).message, urlHintOf(url), options);
  }
  const port = driverOf(endpoint).diagnose;
  if (!port) {
    const schemes = schemesOffering('diagnose');
    return urlFailed(`the doctor checks ${schemes} connections; this URL is ${endpoint.protocol}`, `Give an ${schemes} URL.`, options);
  }
  return port.run(endpoint, addresses, options, formatUrl);
}

/** The hint of a URL that does not parse: its scheme's doctor's, else the first doctor's (s7://, the usual mistake). */
function urlHintOf(url: string): string {
  const scheme = /^\s*([a-z][a-z0-9+.-]*):/i.exec(url)?.[1]?.toLowerCase();
  const ports: DiagnosePort<Endpoint>[] = [];
  for (const d of Object.values(DRIVERS)) {
    const port = d.diagnose as DiagnosePort<Endpoint> | undefined;
    if (!port) continue;
    if (scheme !== undefined && Object.keys(d.urls.schemes).includes(scheme)) return port.urlHint;
    ports.push(port);
  }
  return ports[0]!.urlHint;
}

/** The report of a walk that ended at its `url` step, told to `onStep` as a walk tells its steps. */
function urlFailed(detail: string, hint: string, options: DiagnoseOptions): DoctorReport {
  const step: DoctorStep = { step: 'url', ok: false, detail, hint };
  options.onStep?.(step);
  return { ok: false, steps: [step] };
}
