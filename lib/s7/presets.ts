/** The s7:// URL parameters of each CPU family (the Node-RED connection dialog's presets, the doctor's guesses). */
import { MAX_ITEMS } from './constants';

export type S7CpuPreset = 's7-1500' | 's7-1200' | 's7-400' | 's7-300' | 'logo' | 's7-200';

/** What a CPU preset puts into an s7:// URL: where the CPU answers, and how many items per job it serves. */
export interface S7CpuPresetParams {
  rack?: number;
  slot?: number;
  localTsap?: number;
  remoteTsap?: number;
  /** Absent: DEFAULTS.maxItems (20). 255: as many as the PDU allows. */
  maxItems?: number;
}

/**
 * URL parameters per CPU family (the Node-RED connection dialog's presets).
 * Items per job: Siemens S7-1200, S7-1500 and S7-400 CPUs limit a job by
 * the PDU size only (more than 20 items in one job work on an S7-1200 and an
 * S7-1500, frangoteam/FUXA#694; 36 written to an S7-1500 in one job,
 * S7NetPlus/s7netplus#380; S7-400 as well, S7NetPlus/s7netplus#157), so
 * their presets allow 255 and the PDU decides (19 at PDU 240, 39 at 480, 79
 * at 960). The S7-300 preset keeps the default 20: S7-300 compatible CPUs
 * (VIPA, frangoteam/FUXA#694) serve 20, and a Siemens S7-300 at PDU 240
 * carries 19 anyway. LOGO! and S7-200 negotiate PDU 240 (19 items).
 * TSAPs: an S7-200's CP 243-1 is called at 10.xx, its connection number in
 * the low byte (CP 243-1 manual, section 4.2.3; S7NetPlus TsapPair.cs uses
 * 10.00 / 10.01); a LOGO! at the pair set in LOGO!Soft Comfort, 01.00 / 02.00
 * by default (the simulator's s7-200 and logo profiles accept these).
 */
export const S7_CPU_PRESETS: Readonly<Record<S7CpuPreset, Readonly<S7CpuPresetParams>>> = Object.freeze({
  's7-1500': Object.freeze({ rack: 0, slot: 1, maxItems: MAX_ITEMS }),
  's7-1200': Object.freeze({ rack: 0, slot: 1, maxItems: MAX_ITEMS }),
  's7-400': Object.freeze({ rack: 0, slot: 3, maxItems: MAX_ITEMS }),
  's7-300': Object.freeze({ rack: 0, slot: 2 }),
  logo: Object.freeze({ localTsap: 0x0100, remoteTsap: 0x0200 }),
  's7-200': Object.freeze({ localTsap: 0x1000, remoteTsap: 0x1001 }),
});
