/**
 * The demo plant's process (lib/plant/process.ts), stepped by hand: every
 * cycle is deterministic, so these tests see exactly what the dashboard's
 * visitors see over time, without waiting for a timer.
 */
import { expect } from 'chai';
import { startPlant, type Plant } from '../lib/plant/plant';
import { DemoProcess, MOTOR, SETPOINT_BAND, THERMAL, type ProcessSnapshot } from '../lib/plant/process';
import { DRIVE_CURRENT, TANK_SYMBOLS } from '../lib/plant/tank';
import { connect } from '../lib/connect';
import { S7Client } from '../lib/s7/client';
import { S7Server } from '../lib/s7/server';
import { PlcMemory } from '../lib/sim/memory';
import { parseUrl, type S7Endpoint } from '../lib/url';
import { until } from './support/wait';

const PERIOD_MS = 100;
const STEPS_PER_S = 1000 / PERIOD_MS;

/** A process on fresh memory with the start values `start()` sets, not yet running its timer. */
function fresh(): { process: DemoProcess; db: Buffer } {
  const memory = new PlcMemory();
  const process = new DemoProcess(memory, PERIOD_MS);
  process.start().stop();
  return { process, db: memory.area('DB', 1)! };
}

/** A process that is the program of a simulated S7-1200 (not listening: its mode is all that is used). */
function onCpu(): { process: DemoProcess; db: Buffer; cpu: S7Server } {
  const memory = new PlcMemory();
  const cpu = new S7Server({ profile: 's7-1200', memory });
  const process = new DemoProcess(memory, PERIOD_MS, cpu.cpu);
  process.start().stop();
  return { process, db: memory.area('DB', 1)!, cpu };
}

function run(process: DemoProcess, seconds: number): ProcessSnapshot[] {
  return Array.from({ length: seconds * STEPS_PER_S }, () => process.step());
}

function setRun(db: Buffer, on: boolean): void {
  db[4] = on ? db[4]! | 0x01 : db[4]! & ~0x01;
}

describe('demo process: the simulated plant behind npm start', () => {
  it('starts at ambient temperature with the heater on, and warms up by itself', () => {
    const { process } = fresh();
    expect(process.snapshot().temperature).to.equal(THERMAL.ambient);
    const first = process.step();
    expect(first.heater).to.equal(true);
    const later = run(process, 10).at(-1)!;
    // 10 s of 1 °C/s less the loss near ambient: about 9.2 °C warmer.
    expect(later.temperature).to.be.within(THERMAL.ambient + 8.7, THERMAL.ambient + 9.7);
    expect(later.heater).to.equal(true);
  });

  it('holds the temperature between the thermostat limits, switching the heater on and off, with the motor stopped', () => {
    const { process } = fresh();
    run(process, 60); // warm-up to the lower limit (about 17 s)
    const cycle = run(process, 180);
    const temps = cycle.map((s) => s.temperature);
    // The step of one cycle (< 0.1 °C) is all it may overshoot a limit by.
    expect(Math.min(...temps)).to.be.within(THERMAL.heaterOnBelow - 0.1, THERMAL.heaterOnBelow + 0.5);
    expect(Math.max(...temps)).to.be.within(THERMAL.heaterOffAbove - 0.5, THERMAL.heaterOffAbove + 0.1);
    const switches = cycle.filter((s, i) => i > 0 && s.heater !== cycle[i - 1]!.heater);
    // About 63 s a cycle: at least two on/off pairs in three minutes.
    expect(switches.length).to.be.at.least(5);
    // The heater is on exactly while the temperature rises.
    for (let i = 1; i < cycle.length; i++) {
      const rising = cycle[i]!.temperature > cycle[i - 1]!.temperature;
      expect(rising, `step ${i}`).to.equal(cycle[i]!.heater);
    }
    expect(cycle.every((s) => !s.running && s.speed === 0)).to.equal(true);
  });

  it('the running motor warms the tank: the heater is needed for less of the time, and the band holds', () => {
    const heated = (cycle: ProcessSnapshot[]) => cycle.filter((s) => s.heater).length / cycle.length;
    const stopped = fresh();
    run(stopped.process, 60);
    const idle = run(stopped.process, 600);
    const running = fresh();
    run(running.process, 60);
    setRun(running.db, true);
    run(running.process, 60); // full speed, and the heat of the speed-up settled
    const busy = run(running.process, 600);
    expect(busy.every((s) => s.speed === MOTOR.fullSpeed)).to.equal(true);
    // THERMAL's heat balance: on 28 s of a 63 s cycle stopped, 22 s of a 77 s cycle running
    // (ten minutes are not a whole number of cycles: a few per cent either way).
    expect(heated(idle)).to.be.within(0.38, 0.52);
    expect(heated(busy)).to.be.within(0.22, 0.35);
    expect(heated(busy)).to.be.below(heated(idle) - 0.1);
    for (const cycle of [idle, busy]) {
      const temps = cycle.map((s) => s.temperature);
      expect(Math.min(...temps)).to.be.within(THERMAL.heaterOnBelow - 0.1, THERMAL.heaterOnBelow + 0.5);
      expect(Math.max(...temps)).to.be.within(THERMAL.heaterOffAbove - 0.5, THERMAL.heaterOffAbove + 0.1);
    }
    // Cooling (heater off) is slower with the motor's heat: fewer heater switch-ons in the same time.
    const switchOns = (cycle: ProcessSnapshot[]) => cycle.filter((s, i) => i > 0 && s.heater && !cycle[i - 1]!.heater).length;
    expect(switchOns(busy)).to.be.below(switchOns(idle));
  });

  it('ramps the motor up to full speed on the run command and counts parts only while it runs', () => {
    const { process, db } = fresh();
    run(process, 5);
    expect(process.snapshot()).to.include({ running: false, speed: 0, parts: 0 });
    setRun(db, true);
    const up = run(process, 5);
    expect(up[0]!.running).to.equal(true);
    // 600 rpm/s: full speed (1450) after about 2.4 s.
    expect(up[Math.round(2.3 * STEPS_PER_S)]!.speed).to.be.below(MOTOR.fullSpeed);
    expect(up.at(-1)!.speed).to.equal(MOTOR.fullSpeed);
    // One part every 500 ms while running.
    expect(up.at(-1)!.parts).to.be.within(9, 11);
    setRun(db, false);
    const down = run(process, 3);
    expect(down.at(-1)).to.include({ running: false, speed: 0 });
    const parts = down.at(-1)!.parts;
    run(process, 5);
    expect(process.snapshot().parts).to.equal(parts);
  });

  it('fills and drains the tank between 10 % and 90 %, and the heartbeat counts every 500 ms', () => {
    const { process } = fresh();
    const levels = run(process, 120).map((s) => s.level);
    expect(Math.max(...levels)).to.be.within(90, 90.5);
    expect(Math.min(...levels.slice(30 * STEPS_PER_S))).to.be.within(9.5, 10);
    expect(process.snapshot().heartbeat).to.equal(240);
  });

  it('is deterministic: two processes stepped alike show the same values', () => {
    const a = fresh();
    const b = fresh();
    for (const { process, db } of [a, b]) {
      run(process, 40);
      setRun(db, true);
      run(process, 20);
    }
    expect(a.process.snapshot()).to.deep.equal(b.process.snapshot());
  });
});

describe('demo process: the program of the simulated CPU, it runs only in RUN', () => {
  it('holds every value while the CPU is in STOP, reacts to nothing written meanwhile, and continues from the held values after a restart', () => {
    const { process, db, cpu } = onCpu();
    run(process, 20);
    setRun(db, true);
    run(process, 5);
    const held = process.snapshot();
    expect(held).to.include({ running: true, speed: MOTOR.fullSpeed });
    expect(cpu.stop()).to.equal(true);
    expect(process.programRunning).to.equal(false);
    // A minute of cycles in STOP: nothing moves, not the tank, the thermostat, the counters, the heartbeat.
    expect(run(process, 60).every((s) => JSON.stringify(s) === JSON.stringify(held))).to.equal(true);
    // The CPU in STOP still takes writes; its program does not react to them.
    setRun(db, false);
    run(process, 5);
    expect(process.snapshot()).to.deep.equal(held);
    expect(cpu.start()).to.equal(true);
    expect(process.programRunning).to.equal(true);
    const after = process.step();
    // One cycle on from where it stopped: the level moves by one step, the motor starts ramping down.
    expect(Math.abs(after.level - held.level)).to.be.within(0.29, 0.41);
    expect(after.speed).to.equal(MOTOR.fullSpeed - MOTOR.rampDown / STEPS_PER_S);
    expect(after.parts).to.equal(held.parts);
  });

  it('a stop and restart shift the process in time and change nothing else', () => {
    const plain = fresh();
    const stopped = onCpu();
    run(plain.process, 30);
    run(stopped.process, 30);
    stopped.cpu.stop();
    run(stopped.process, 45);
    stopped.cpu.start();
    run(plain.process, 30);
    run(stopped.process, 30);
    expect(stopped.process.snapshot()).to.deep.equal(plain.process.snapshot());
  });

  describe('the demo plant', () => {
    let plant: Plant;
    let client: S7Client;
    before(async () => {
      plant = await startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 } });
      client = new S7Client(parseUrl(`${plant.urls.s7}&control=true`) as S7Endpoint);
      await client.connect();
    });
    after(async () => {
      await client?.close();
      await plant?.close();
    });

    const level = async () => (await client.read(['DB1.DBD0:REAL']))['DB1.DBD0:REAL'] as number;

    it('a PLC stop from a client freezes the values it serves, a warm restart sets them moving again', async () => {
      // Running: the tank level changes within a few cycles.
      const before = await level();
      await until(() => plant.process.snapshot().level !== before, 3000, 'the level moving');
      await client.stop();
      expect(plant.s7.state).to.equal('STOP');
      expect(plant.s7.diagnostics[0]).to.include({ eventId: 0x4304 });
      // Read over the socket for ten cycles of the process: always the same value.
      const held = await level();
      const start = Date.now();
      let reads = 0;
      while (Date.now() - start < 10 * 100) {
        expect(await level()).to.equal(held);
        reads++;
      }
      expect(reads).to.be.at.least(5);
      expect(plant.process.snapshot().level).to.equal(held);
      await client.hotStart();
      expect(plant.s7.state).to.equal('RUN');
      const deadline = Date.now() + 3000;
      let now = held;
      while (now === held && Date.now() < deadline) now = await level();
      expect(now).to.not.equal(held);
    });
  });
});

describe('demo process: the optimized DB "Tank" (DB2), served by name over S7CommPlus', function () {
  this.timeout(20000);
  let plant: Plant;
  before(async () => {
    plant = await startPlant({ ports: { s7: 0, fetch: 0, write: 0, freeport: 0 } });
    plant.process.stop();
  });
  after(async () => {
    await plant?.close();
  });

  it('keeps the phase, the drive and the level of the last five seconds in step with DB1', () => {
    const db = plant.memory.area('DB', 1)!;
    setRun(db, true);
    const seen = run(plant.process, 12);
    const last = seen.at(-1)!;
    const tank = plant.tank.snapshot();
    expect(tank.drive).to.deep.equal({
      running: last.running,
      speed: last.speed,
      current: Math.fround(DRIVE_CURRENT.idle + (DRIVE_CURRENT.full * last.speed) / MOTOR.fullSpeed),
    });
    expect(last.speed).to.equal(MOTOR.fullSpeed);
    // Newest first, one a second: the level at the end of each of the last five whole seconds.
    const perSecond = seen.filter((_, i) => (i + 1) % STEPS_PER_S === 0).map((x) => x.level);
    expect(tank.levels).to.deep.equal(perSecond.slice(-5).reverse());
    expect(tank.phase).to.equal(last.level > seen.at(-2)!.level ? 'Filling' : 'Draining');
    setRun(db, false);
    const stopped = run(plant.process, 3).at(-1)!;
    expect(stopped.speed).to.equal(0);
    expect(plant.tank.snapshot().drive).to.deep.equal({ running: false, speed: 0, current: 0 });
  });

  it('says Draining from the top of the tank (90 %) and Filling again from its bottom (10 %)', () => {
    const turns: { phase: string; level: number }[] = [];
    for (let i = 0; i < 90 * STEPS_PER_S; i++) {
      const { level } = plant.process.step();
      const phase = plant.tank.snapshot().phase;
      if (turns.at(-1)?.phase !== phase) turns.push({ phase, level });
    }
    const later = turns.slice(1);
    expect(later.map((t) => t.phase).slice(0, 2)).to.have.members(['Filling', 'Draining']);
    for (const t of later) {
      if (t.phase === 'Draining') expect(t.level).to.be.at.least(90);
      else expect(t.level).to.be.at.most(10);
    }
  });

  it('switches the heater around "Tank".Setpoint: a setpoint written by name over s7plus:// moves the band the temperature holds', async () => {
    const client = await connect(plant.urls.s7plus);
    try {
      expect(await client.read([TANK_SYMBOLS.setpoint])).to.deep.equal({
        [TANK_SYMBOLS.setpoint]: (THERMAL.heaterOnBelow + THERMAL.heaterOffAbove) / 2,
      });
      await client.write({ [TANK_SYMBOLS.setpoint]: 30 });
      expect(plant.tank.snapshot().setpoint).to.equal(30);
      run(plant.process, 120); // settle into the new band
      const temps = run(plant.process, 180).map((x) => x.temperature);
      expect(Math.min(...temps)).to.be.within(30 - SETPOINT_BAND - 0.1, 30 - SETPOINT_BAND + 0.5);
      expect(Math.max(...temps)).to.be.within(30 + SETPOINT_BAND - 0.5, 30 + SETPOINT_BAND + 0.1);
      // What the process keeps is what a client reads by name.
      const read = await client.read([TANK_SYMBOLS.phase, '"Tank".Drive', TANK_SYMBOLS.levels]);
      const tank = plant.tank.snapshot();
      expect(read).to.deep.equal({
        [TANK_SYMBOLS.phase]: tank.phase,
        '"Tank".Drive': { Running: false, Speed: 0, Current: 0 },
        [TANK_SYMBOLS.levels]: tank.levels,
      });
    } finally {
      await client.close();
    }
  });
});
