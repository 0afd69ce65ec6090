/**
 * The connection doctor of any URL: the URL parsed here (a URL that does not
 * parse, or whose protocol has no doctor, is a failed `url` step), then the
 * steps of its driver's diagnose port (lib/drivers.ts: lib/s7/doctor for
 * s7://, lib/s7plus/doctor for s7plus://), walked by lib/doctor/walk.ts. Every
 * doctor gives the same report: steps with ok, detail and a hint.
 */
import type { DiagnosePort, DiagnoseOptions, DoctorReport } from '../doctor-steps';
import { DRIVERS, driverOf, schemesOffering, type Endpoint } from '../drivers';
import { formatUrl, parseUrl } from '../url';
import { DoctorWalk } from './walk';

export type { DiagnoseOptions, DoctorReport, DoctorStep } from '../doctor-steps';

/**
 * Diagnoses the connection to a PLC, step by step, up to the first failure.
 * Resolves the report; rejects only with ABORTED when `options.signal`
 * aborts. Nothing is written to the PLC.
 */
export async function diagnose(url: string, addresses: readonly string[] = [], options: DiagnoseOptions = {}): Promise<DoctorReport> {
  const walk = new DoctorWalk(options); // a bad timeout is refused here, before anything else
  try {
    await walk.walk(async () => {
      let endpoint: Endpoint;
      try {
        endpoint = parseUrl(url);
      } catch (err) {
        return walk.fail('url', (err as Error).message, urlHintOf(url));
      }
      const port = driverOf(endpoint).diagnose;
      if (!port) {
        const schemes = schemesOffering('diagnose');
        return walk.fail('url', `the doctor checks ${schemes} connections; this URL is ${endpoint.protocol}`, `Give an ${schemes} URL.`);
      }
      await port.run(endpoint, addresses, walk, formatUrl);
    });
  } finally {
    walk.dispose();
  }
  return walk.report();
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
