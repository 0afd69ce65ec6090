/**
 * The demo plant's alarms (issue #33): the tank's high level, as the program of
 * each generation raises it. The program (DemoProcess) sets the bit
 * DEMO_HIGH_LEVEL.trigger while the level is at or above `above` % and clears
 * it below `clearBelow` % (a hysteresis, so a level at the limit does not
 * chatter); the CPUs' alarm engines watch that bit:
 *
 * - the classic S7-300 an ALARM_SQ (SFC 17: it needs acknowledging) with the
 *   level (REAL) as its associated value SD_1;
 * - the S7-1200 a Program_Alarm of alarm class 1 ("Acknowledgement"), its texts
 *   in en-US and de-DE with the level in their placeholder.
 *
 * M10.0 lies outside "Plant" (DB1) and "Tank" (DB2), whose layouts other tests
 * and users' flows read.
 */
import type { AlarmDefinition } from '../alarms/model';

export const DEMO_HIGH_LEVEL = Object.freeze({
  /** The flag the program sets: a memory bit of the CPU both generations share. */
  trigger: 'M10.0',
  /** The flag's byte and bit, for the program's writeBit. */
  byte: 10,
  bit: 0,
  above: 85,
  clearBelow: 80,
  /** The associated value: the level, "Plant".Level. */
  value: 'DB1.DBD0:REAL',
});

/** The classic CPU's message number of the tank's high level (EV_ID), and the S7-1200's CPU alarm id. */
export const DEMO_ALARM_IDS = Object.freeze({ classic: 0x101, program: 1 });

const TEXTS = Object.freeze({
  'en-US': 'Tank level high: @1%.1f@ %',
  'de-DE': 'Tankfüllstand hoch: @1%.1f@ %',
});

/** The S7-300's alarm block: ALARM_SQ, acknowledged by the operator. */
export const CLASSIC_DEMO_ALARMS: readonly AlarmDefinition[] = Object.freeze([
  {
    id: DEMO_ALARM_IDS.classic,
    kind: 'ALARM_SQ',
    texts: { ...TEXTS },
    needsAck: true,
    trigger: DEMO_HIGH_LEVEL.trigger,
    values: [DEMO_HIGH_LEVEL.value],
  },
]);

/** The S7-1200's Program_Alarm. */
export const PROGRAM_DEMO_ALARMS: readonly AlarmDefinition[] = Object.freeze([
  {
    id: DEMO_ALARM_IDS.program,
    kind: 'Program_Alarm',
    texts: { ...TEXTS },
    priority: 8,
    needsAck: true,
    trigger: DEMO_HIGH_LEVEL.trigger,
    values: [DEMO_HIGH_LEVEL.value],
  },
]);
