/**
 * The demo plant's DB1 as its PLC programmer would hand it over: the source
 * TIA Portal writes with "Generate source from blocks" for a global DB
 * "Plant" with standard access (S7_Optimized_Access := 'FALSE'), DB number 1,
 * in the `VAR … END_VAR` form TIA Portal writes global DBs in today.
 * Compiled (compileSymbols) it places every member exactly where the demo
 * process reads and writes it (DEMO_TAGS, lib/plant/process.ts); a test
 * holds the two together, and holds demo/Plant.db (the same text as the
 * file TIA writes: UTF-8 with BOM, CRLF) to this one.
 *
 * It ships inside the library so that `plcwire demo` and `npm start` build
 * their simulated S7-1200 from it, and the demo flow's connection node
 * carries it to read the plant by name.
 */
import type { SymbolSource } from '../symbols/model';

export const PLANT_SOURCE: SymbolSource = Object.freeze({
  name: 'Plant.db',
  content: `DATA_BLOCK "Plant"
{ S7_Optimized_Access := 'FALSE' }
AUTHOR : plcwire
FAMILY : Demo
NAME : Plant
VERSION : 0.1
RETAIN
//Demo plant: heated tank with feed motor, parts counter and the life signs between PLC and PC. Standard access (PUT/GET reads it by offset).
   VAR 
      Level : Real := 20.0;   // Tank level in %; fills at 4 %/s up to 90 %, drains at 3 %/s down to 10 %
      MotorRun : Bool;   // Run command from the operator (dashboard switch, HMI)
      MotorRunning : Bool;   // Motor turns (speed > 0)
      Heater : Bool;   // Tank heater, switched by the thermostat 7.5 °C below and above the operator's setpoint ("Tank".Setpoint, 42.5 °C at start: on below 35 °C, off above 50 °C)
      MotorSpeed : Int;   // Actual speed in rpm; ramps up at 600 rpm/s to 1450, down at 900 rpm/s
      Parts : DInt;   // Parts made: +1 every 500 ms while the motor turns
      PlcHeartbeat : Int;   // PLC life sign: +1 every 500 ms in RUN, 0..32767
      PcHeartbeat : Int;   // PC life sign: written by the PC (Node-RED heartbeat node), not used by the PLC
      Temperature : Real := 20.0;   // Tank temperature in °C
   END_VAR


BEGIN

END_DATA_BLOCK

`,
});

/** The DB number of each block of PLANT_SOURCE (a TIA source does not carry it): the `db` option of compileSymbols. */
export const PLANT_DB_NUMBERS: Readonly<Record<string, number>> = Object.freeze({ Plant: 1 });

/**
 * The demo plant's optimized DB "Tank" (DB2): what the program keeps about the
 * tank and its feed drive, and the operator's setpoint, in a block with
 * Optimized block access as TIA Portal V17+ creates it by default. Its members
 * have no offsets: PUT/GET refuses the block, S7CommPlus (`s7plus://`) reads
 * and writes it by name, browsed from the PLC, no source file needed. The
 * simulator lays it out for its own storage only (lib/s7plus/server/model.ts);
 * the demo process finds its members by name there (lib/plant/tank.ts).
 */
export const TANK_SOURCE: SymbolSource = Object.freeze({
  name: 'Tank.db',
  content: `DATA_BLOCK "Tank"
{ S7_Optimized_Access := 'TRUE' }
AUTHOR : plcwire
FAMILY : Demo
NAME : Tank
VERSION : 0.1
NON_RETAIN
//Demo plant: the tank's phase, the operator's temperature setpoint, the feed drive and the level of the last seconds. Optimized access: read by name over S7CommPlus.
   VAR 
      Phase : String[16] := 'Filling';   // What the tank does: Filling or Draining
      Setpoint : Real := 42.5;   // Temperature setpoint in °C, from the operator; the thermostat switches the heater 7.5 °C below and above it
      Drive : Struct   // The feed motor's drive
         Running : Bool;   // Motor turns (speed > 0)
         Speed : Int;   // Actual speed in rpm
         Current : Real;   // Motor current in A: 0 stopped, 1.2 A turning plus 4.3 A at full speed
      END_STRUCT;
      Levels : Array[0..4] of Real;   // Tank level in % of the last five seconds, newest first
   END_VAR


BEGIN

END_DATA_BLOCK

`,
});

/** The DB number of the optimized block TANK_SOURCE. */
export const TANK_DB_NUMBERS: Readonly<Record<string, number>> = Object.freeze({ Tank: 2 });
