/** The S7 simulator: S7Server (a CPU over ISO-on-TCP), its profiles, jobs and system services. */
export * from './server';
