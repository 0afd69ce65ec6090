/**
 * The CPU families the connection doctor tells apart: how each is usually
 * addressed (rack/slot or a TSAP pair, from the connection presets), the
 * addressings it tries when the URL's is refused, and the family an order
 * code or module type names.
 */
import type { S7Endpoint } from '../url';
import { hex4 } from '../../values/text';
import { S7_CPU_PRESETS, type S7CpuPreset } from '../presets';
import type { PlcInfo } from '../client';
import { localTsapFor, remoteTsapFor } from '../tsap';

export type Family = 'S7-300' | 'S7-400' | 'S7-1200' | 'S7-1500' | 'S7-200' | 'LOGO!';

/** How a CPU family is reached, from the connection presets (url.ts S7_CPU_PRESETS). */
export function usualAddressing(): string {
  const p = S7_CPU_PRESETS;
  const rs = (k: S7CpuPreset) => `rack ${p[k].rack}, slot ${p[k].slot}`;
  const ts = (k: S7CpuPreset) => `localTsap=${hex4(p[k].localTsap!)}&remoteTsap=${hex4(p[k].remoteTsap!)}`;
  return (
    `Usual values: S7-300 ${rs('s7-300')}; S7-400 ${rs('s7-400')} (or the slot the CPU sits in); S7-1200/1500 ${rs('s7-1200')} (or slot 0); ` +
    `S7-200 with a CP 243-1 ${ts('s7-200')} (as set in the Ethernet wizard); LOGO! ${ts('logo')} (as set in LOGO!Soft Comfort).`
  );
}

/** What a connection request tries: rack/slot, or a TSAP pair. */
export interface Addressing {
  callingTsap: number;
  calledTsap: number;
  /** How to say it in a URL query. */
  query: string;
  /** How to say it in words. */
  label: string;
  /** The family this addressing points to when the CPU accepts it. */
  family: string;
}

export function addressingOf(e: S7Endpoint): Addressing {
  if (e.remoteTsap !== undefined) {
    return tsapPair(e.localTsap!, e.remoteTsap, '');
  }
  return {
    callingTsap: localTsapFor(e.connectionType),
    calledTsap: remoteTsapFor(e.connectionType, e.rack, e.slot),
    query: `rack=${e.rack}&slot=${e.slot}`,
    label: `rack ${e.rack}, slot ${e.slot}`,
    family: '',
  };
}

function tsapPair(local: number, remote: number, family: string): Addressing {
  return {
    callingTsap: local,
    calledTsap: remote,
    query: `localTsap=${hex4(local)}&remoteTsap=${hex4(remote)}`,
    label: `local TSAP 0x${hex4(local)}, remote TSAP 0x${hex4(remote)}`,
    family,
  };
}

/** The addressings tried when the URL's is refused: the usual slots first (a rack/slot CPU accepts a foreign TSAP too), then the TSAP pairs. */
export function alternatives(e: S7Endpoint): Addressing[] {
  const slot = (s: number, family: string): Addressing => ({
    callingTsap: localTsapFor(e.connectionType),
    calledTsap: remoteTsapFor(e.connectionType, 0, s),
    query: `rack=0&slot=${s}`,
    label: `rack 0, slot ${s}`,
    family,
  });
  const pair = (k: 's7-200' | 'logo', family: string): Addressing => {
    const { localTsap, remoteTsap } = S7_CPU_PRESETS[k];
    return tsapPair(localTsap!, remoteTsap!, family);
  };
  const tried = addressingOf(e);
  return [
    slot(1, 'an S7-1200/1500 (or ET 200SP CPU)'),
    slot(2, 'an S7-300 (or an S7-400 in slot 2)'),
    slot(3, 'an S7-400'),
    slot(0, 'an S7-1200/1500'),
    pair('s7-200', 'an S7-200 with a CP 243-1'),
    pair('logo', 'a LOGO!'),
  ].filter((a) => a.calledTsap !== tried.calledTsap || a.callingTsap !== tried.callingTsap);
}
/** The family an order code (MLFB) or module type names; undefined when it is not one we know. */
export function familyOf(info: Pick<PlcInfo, 'orderCode' | 'moduleTypeName'>): Family | undefined {
  const code = (info.orderCode ?? '').replace(/\s+/g, '').toUpperCase();
  if (/^6ES721\d-1/.test(code)) return 'S7-1200';
  if (/^6ES721\d-/.test(code)) return 'S7-200';
  if (/^6ES751\d-/.test(code)) return 'S7-1500';
  if (/^6ES731\d-/.test(code)) return 'S7-300';
  if (/^6ES741\d-/.test(code)) return 'S7-400';
  if (/^6ED1052-/.test(code)) return 'LOGO!';
  const name = info.moduleTypeName ?? '';
  if (/CPU\s*12\d\d/.test(name)) return 'S7-1200';
  if (/CPU\s*15\d\d/.test(name)) return 'S7-1500';
  if (/CPU\s*3\d\d/.test(name)) return 'S7-300';
  if (/CPU\s*4\d\d/.test(name)) return 'S7-400';
  if (/LOGO/i.test(name)) return 'LOGO!';
  return undefined;
}
