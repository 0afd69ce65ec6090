/**
 * A small simulated process for the demo and for users' flow tests: a tank
 * whose level rises and falls, a motor with run/stop, a parts counter, a
 * heated tank whose temperature a thermostat holds (the running motor warms
 * it further) and the PLC's heartbeat. Every cycle is a pure function of the
 * memory and the cycle count, so a test that calls `step()` sees the same
 * values every time. It runs on PlcMemory (S7 and
 * FETCH/WRITE simulators) with the memory map below; the same values are
 * mirrored into freeport stations by the demo.
 *
 * The process plays the PLC's program (and the plant it controls), so it
 * runs only while the CPU it is given is in RUN: in STOP the CPU still
 * answers reads and writes, but nothing in DB1 changes (the heartbeat stops
 * counting too), and a restart continues from the values held, as with a
 * retentive DB.
 *
 *   DB1.DBD0:REAL   tank level, %            (process)
 *   DB1.DBX4.0      motor run command        (written by the operator)
 *   DB1.DBX4.1      motor running            (process)
 *   DB1.DBX4.2      heater on                (process, thermostat)
 *   DB1.DBW6:INT    motor speed, rpm         (process, ramps)
 *   DB1.DBD8:DINT   parts counter            (process, while running)
 *   DB1.DBW12:INT   PLC heartbeat counter    (process, every 500 ms)
 *   DB1.DBW14:INT   PC heartbeat             (written by the heartbeat node)
 *   DB1.DBD16:REAL  temperature, °C          (process)
 *
 * DB1 is the data block "Plant" of lib/plant/source.ts (PLANT_SOURCE): the
 * same members by name (DEMO_SYMBOLS), which compile to these addresses.
 *
 * Given the optimized DB "Tank" (DB2, lib/plant/tank.ts) the process keeps it
 * too: the phase, the drive's running, speed and current, the level of the
 * last five seconds; and its thermostat switches around "Tank".Setpoint, the
 * operator's setpoint (THERMAL's limits are those of its start value, 42.5 °C).
 */
import type { PlcMemory } from '../sim/memory';
import { DEMO_HIGH_LEVEL } from './alarms';
import type { TankBlock } from './tank';

/** The CPU the program runs on: S7Server#cpu (or anything with its RUN/STOP mode). */
export interface ProgramCpu {
  readonly mode: string;
}

export const DEMO_TAGS = Object.freeze({
  level: 'DB1.DBD0:REAL',
  run: 'DB1.DBX4.0',
  running: 'DB1.DBX4.1',
  heater: 'DB1.DBX4.2',
  speed: 'DB1.DBW6:INT',
  parts: 'DB1.DBD8:DINT',
  plcHeartbeat: 'DB1.DBW12:INT',
  pcHeartbeat: 'DB1.DBW14:INT',
  temperature: 'DB1.DBD16:REAL',
});

/** The same tags by name: the members of "Plant" (PLANT_SOURCE, lib/plant/source.ts), compiled to DEMO_TAGS' addresses. */
export const DEMO_SYMBOLS: Readonly<Record<keyof typeof DEMO_TAGS, string>> = Object.freeze({
  level: '"Plant".Level',
  run: '"Plant".MotorRun',
  running: '"Plant".MotorRunning',
  heater: '"Plant".Heater',
  speed: '"Plant".MotorSpeed',
  parts: '"Plant".Parts',
  plcHeartbeat: '"Plant".PlcHeartbeat',
  pcHeartbeat: '"Plant".PcHeartbeat',
  temperature: '"Plant".Temperature',
});

export interface ProcessSnapshot {
  level: number;
  running: boolean;
  heater: boolean;
  speed: number;
  parts: number;
  heartbeat: number;
  temperature: number;
}

/** DB1.DBB4's bits. */
const RUN = 0x01;
const RUNNING = 0x02;
const HEATER = 0x04;

/** The motor: full speed, and how fast it ramps up and down (rpm per second). */
export const MOTOR = Object.freeze({ fullSpeed: 1450, rampUp: 600, rampDown: 900 });

/**
 * The tank's heat balance, per second: the heater adds `heaterRate` °C, the
 * motor at full speed `motorRate` °C (in proportion to its speed), and the tank
 * loses `loss` of its excess over `ambient`. The thermostat switches the heater
 * on below `heaterOnBelow` and off above `heaterOffAbove`, so the temperature
 * swings between the two: a cycle of about 63 s with the motor stopped, the
 * heater on for 45 % of it; the running motor's heat shortens the heating and
 * slows the cooling, to a cycle of about 77 s with the heater on for 28 %.
 */
export const THERMAL = Object.freeze({ ambient: 20, heaterOnBelow: 35, heaterOffAbove: 50, heaterRate: 1, motorRate: 0.15, loss: 0.02 });

/** How far below and above "Tank".Setpoint the thermostat switches (half THERMAL's band). */
export const SETPOINT_BAND = (THERMAL.heaterOffAbove - THERMAL.heaterOnBelow) / 2;

export class DemoProcess {
  private timer: NodeJS.Timeout | undefined;
  private ticks = 0;
  private filling = true;

  constructor(
    private readonly memory: PlcMemory,
    private readonly periodMs = 100,
    private readonly cpu?: ProgramCpu,
    private readonly tank?: TankBlock,
  ) {}

  start(): this {
    if (!this.timer) {
      const db = this.db();
      // The source's start values (PLANT_SOURCE) where the memory was not built from it: a blank DB1.
      if (db.readFloatBE(0) === 0) db.writeFloatBE(20, 0);
      if (db.readFloatBE(16) === 0) db.writeFloatBE(THERMAL.ambient, 16);
      this.tank?.startLevels(db.readFloatBE(0));
      this.timer = setInterval(() => this.step(), this.periodMs);
      this.timer.unref();
    }
    return this;
  }

  stop(): void {
    clearInterval(this.timer);
    this.timer = undefined;
  }

  /** Whether the program runs: always without a CPU, else while the CPU is in RUN. */
  get programRunning(): boolean {
    return this.cpu === undefined || this.cpu.mode === 'RUN';
  }

  /**
   * One cycle of the process; public so tests can step it deterministically.
   * With the CPU in STOP there is no cycle: the values are returned as held.
   */
  step(): ProcessSnapshot {
    if (!this.programRunning) return this.snapshot();
    const db = this.db();
    const dt = this.periodMs / 1000;
    this.ticks++;
    let level = db.readFloatBE(0);
    level += (this.filling ? 4 : -3) * dt;
    if (level >= 90) this.filling = false;
    if (level <= 10) this.filling = true;
    level = Math.min(100, Math.max(0, level));
    db.writeFloatBE(level, 0);
    this.highLevel(level);

    const run = (db[4]! & RUN) !== 0;
    let speed = db.readInt16BE(6);
    speed = run ? Math.min(MOTOR.fullSpeed, speed + Math.round(MOTOR.rampUp * dt)) : Math.max(0, speed - Math.round(MOTOR.rampDown * dt));
    db.writeInt16BE(speed, 6);
    const running = speed > 0;
    if (running && this.ticks % Math.max(1, Math.round(0.5 / dt)) === 0) db.writeInt32BE((db.readInt32BE(8) + 1) | 0, 8);

    if (this.ticks % Math.max(1, Math.round(0.5 / dt)) === 0) db.writeInt16BE((db.readInt16BE(12) + 1) & 0x7fff, 12);

    let temperature = db.readFloatBE(16);
    let heater = (db[4]! & HEATER) !== 0;
    const [onBelow, offAbove] = this.thermostat();
    if (temperature < onBelow) heater = true;
    else if (temperature > offAbove) heater = false;
    const rise =
      (heater ? THERMAL.heaterRate : 0) + (THERMAL.motorRate * speed) / MOTOR.fullSpeed - THERMAL.loss * (temperature - THERMAL.ambient);
    temperature += rise * dt;
    db.writeFloatBE(temperature, 16);
    db[4] = (db[4]! & ~(RUNNING | HEATER)) | (running ? RUNNING : 0) | (heater ? HEATER : 0);
    this.tank?.update({
      filling: this.filling,
      speed,
      fullSpeed: MOTOR.fullSpeed,
      level,
      shiftLevels: this.ticks % Math.max(1, Math.round(1 / dt)) === 0,
    });
    return this.snapshot();
  }

  /**
   * The tank's high level (lib/plant/alarms.ts): the flag the alarm blocks watch, set at or above `above` and cleared
   * below `clearBelow`; written through the memory (its 'write' event is what the alarm engines hear), on a change only.
   */
  private highLevel(level: number): void {
    const { byte, bit, above, clearBelow } = DEMO_HIGH_LEVEL;
    const m = this.memory.area('M');
    if (!m || m.length <= byte) return;
    const high = (m[byte]! & (1 << bit)) !== 0;
    if (!high && level >= above) this.memory.writeBit('M', 0, byte, bit, true);
    else if (high && level < clearBelow) this.memory.writeBit('M', 0, byte, bit, false);
  }

  /** The thermostat's limits: around the operator's setpoint in "Tank" when there is one (and it is a number), else THERMAL's. */
  private thermostat(): [number, number] {
    const setpoint = this.tank?.setpoint;
    if (setpoint === undefined || !Number.isFinite(setpoint)) return [THERMAL.heaterOnBelow, THERMAL.heaterOffAbove];
    return [setpoint - SETPOINT_BAND, setpoint + SETPOINT_BAND];
  }

  snapshot(): ProcessSnapshot {
    const db = this.db();
    return {
      level: db.readFloatBE(0),
      running: (db[4]! & RUNNING) !== 0,
      heater: (db[4]! & HEATER) !== 0,
      speed: db.readInt16BE(6),
      parts: db.readInt32BE(8),
      heartbeat: db.readInt16BE(12),
      temperature: db.readFloatBE(16),
    };
  }

  private db(): Buffer {
    const db = this.memory.area('DB', 1);
    if (!db || db.length < 20) throw new Error('the demo process needs DB1 of at least 20 bytes');
    return db;
  }
}
