/**
 * The optimized DB "Tank" (DB2, TANK_SOURCE) as the demo process keeps it.
 * A client never sees an offset of it: it reads the members by name over
 * S7CommPlus. The simulator stores the block by the standard layout rules
 * (lib/s7plus/server/model.ts), so the process finds each member's place in
 * the simulator's own table by its name, once, and writes it there.
 *
 *   "Tank".Phase           STRING[16]  'Filling' or 'Draining'          (process)
 *   "Tank".Setpoint        REAL        temperature setpoint, °C          (written by the operator)
 *   "Tank".Drive.Running   BOOL        motor turns                       (process)
 *   "Tank".Drive.Speed     INT         motor speed, rpm                  (process)
 *   "Tank".Drive.Current   REAL        motor current, A                  (process)
 *   "Tank".Levels          ARRAY[0..4] OF REAL, the level of the last five seconds, newest first (process)
 */
import type { PlcMemory } from '../sim/memory';
import type { SymbolTable } from '../symbols/model';
import { TANK_DB_NUMBERS } from './source';

export const TANK_SYMBOLS = Object.freeze({
  phase: '"Tank".Phase',
  setpoint: '"Tank".Setpoint',
  running: '"Tank".Drive.Running',
  speed: '"Tank".Drive.Speed',
  current: '"Tank".Drive.Current',
  levels: '"Tank".Levels',
});

/** The data block number of "Tank". */
export const TANK_DB = TANK_DB_NUMBERS.Tank!;

/** The drive's current: nothing while stopped, `idle` A while turning and `full` A more at full speed (in proportion to the speed). */
export const DRIVE_CURRENT = Object.freeze({ idle: 1.2, full: 4.3 });

/** Elements of "Tank".Levels. */
const LEVELS = 5;

export interface TankSnapshot {
  phase: string;
  setpoint: number;
  drive: { running: boolean; speed: number; current: number };
  levels: number[];
}

interface Place {
  readonly byte: number;
  readonly bit: number;
}

/** The block "Tank" in the simulator's memory; `table` is the simulator's own (S7PlusService#model.table), which places the optimized block. */
export class TankBlock {
  private readonly at: Readonly<Record<keyof typeof TANK_SYMBOLS, Place>>;
  private readonly phaseLength: number;

  constructor(
    private readonly memory: PlcMemory,
    table: SymbolTable,
  ) {
    const place = (name: string): Place => {
      const entry = table.entries.find((e) => e.name === name && e.db === TANK_DB);
      if (!entry || entry.byte === null) throw new Error(`the demo's simulator holds no ${name} in DB${TANK_DB}`);
      return { byte: entry.byte, bit: entry.bit ?? 0 };
    };
    this.at = Object.freeze({
      phase: place(TANK_SYMBOLS.phase),
      setpoint: place(TANK_SYMBOLS.setpoint),
      running: place(TANK_SYMBOLS.running),
      speed: place(TANK_SYMBOLS.speed),
      current: place(TANK_SYMBOLS.current),
      levels: place(TANK_SYMBOLS.levels),
    });
    this.phaseLength = table.entries.find((e) => e.name === TANK_SYMBOLS.phase)!.stringLength;
    this.image();
  }

  /** The operator's setpoint as the PLC holds it. */
  get setpoint(): number {
    return this.image().readFloatBE(this.at.setpoint.byte);
  }

  /** One cycle's values of the process; `shiftLevels` pushes `level` in front of "Tank".Levels (once a second). */
  update(values: { filling: boolean; speed: number; fullSpeed: number; level: number; shiftLevels: boolean }): void {
    const db = this.image();
    const phase = Buffer.from(values.filling ? 'Filling' : 'Draining', 'latin1').subarray(0, this.phaseLength);
    // STRING: maximum length, actual length, characters (the maximum is the source's, written with the start values).
    db[this.at.phase.byte + 1] = phase.length;
    phase.copy(db, this.at.phase.byte + 2);
    const running = values.speed > 0;
    const { byte, bit } = this.at.running;
    db[byte] = running ? db[byte]! | (1 << bit) : db[byte]! & ~(1 << bit);
    db.writeInt16BE(values.speed, this.at.speed.byte);
    db.writeFloatBE(running ? DRIVE_CURRENT.idle + (DRIVE_CURRENT.full * values.speed) / values.fullSpeed : 0, this.at.current.byte);
    if (values.shiftLevels) {
      const first = this.at.levels.byte;
      db.copyWithin(first + 4, first, first + 4 * (LEVELS - 1));
      db.writeFloatBE(values.level, first);
    }
  }

  /** Fills "Tank".Levels with `level` where it holds nothing yet (a fresh start), so the history never shows a 0 that was not. */
  startLevels(level: number): void {
    const db = this.image();
    const first = this.at.levels.byte;
    if (db.subarray(first, first + 4 * LEVELS).every((b) => b === 0))
      for (let i = 0; i < LEVELS; i++) db.writeFloatBE(level, first + 4 * i);
  }

  snapshot(): TankSnapshot {
    const db = this.image();
    const phase = this.at.phase.byte;
    return {
      phase: db.toString('latin1', phase + 2, phase + 2 + db[phase + 1]!),
      setpoint: db.readFloatBE(this.at.setpoint.byte),
      drive: {
        running: (db[this.at.running.byte]! & (1 << this.at.running.bit)) !== 0,
        speed: db.readInt16BE(this.at.speed.byte),
        current: db.readFloatBE(this.at.current.byte),
      },
      levels: Array.from({ length: LEVELS }, (_, i) => db.readFloatBE(this.at.levels.byte + 4 * i)),
    };
  }

  private image(): Buffer {
    const db = this.memory.area('DB', TANK_DB);
    if (!db) throw new Error(`the demo process needs DB${TANK_DB} "Tank" (TANK_SOURCE) in the simulator's memory`);
    return db;
  }
}
