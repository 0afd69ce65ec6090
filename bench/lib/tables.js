'use strict';
// Tag tables of the benchmark and the DB1 image each one reads. Every client
// reads the same nodes7-style addresses ('DB1,INT2', 'DB1,REAL4', 'DB1,X6.0',
// 'DB1,S8.16'), which all three libraries accept; the image holds values the
// workers check on the first poll, so a client that is fast but wrong shows up.

const DB1_SIZE = 32768;
const STRING_LENGTH = 16;

/** Small deterministic PRNG (mulberry32), so every run reads the same table. */
function prng(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/** Scattered: INT 40 %, REAL 30 %, BOOL 20 %, STRING[16] 10 %; gaps of 0–12 bytes, one in ten 100–300 bytes. */
function scattered(count, seed) {
  const rnd = prng(seed);
  const tags = [];
  let offset = 0;
  for (let i = 0; i < count; i++) {
    const r = rnd();
    const type = r < 0.4 ? 'INT' : r < 0.7 ? 'REAL' : r < 0.9 ? 'BOOL' : 'STRING';
    if (type !== 'BOOL' && offset % 2) offset++; // S7 words start on even bytes
    tags.push(makeTag(type, offset, type === 'BOOL' ? Math.floor(rnd() * 8) : 0, rnd));
    offset += sizeOf(type);
    offset += rnd() < 0.1 ? 100 + Math.floor(rnd() * 200) : Math.floor(rnd() * 13);
  }
  if (offset > DB1_SIZE) throw new Error('table does not fit DB1');
  return tags;
}

/** Contiguous: INT and REAL alternating with no gap. */
function contiguous(count, seed) {
  const rnd = prng(seed);
  const tags = [];
  let offset = 0;
  for (let i = 0; i < count; i++) {
    const type = i % 2 ? 'REAL' : 'INT';
    tags.push(makeTag(type, offset, 0, rnd));
    offset += sizeOf(type);
  }
  return tags;
}

function sizeOf(type) {
  return { INT: 2, REAL: 4, BOOL: 1, STRING: STRING_LENGTH + 2 }[type];
}

function makeTag(type, offset, bit, rnd) {
  switch (type) {
    case 'INT':
      return { type, offset, bit, address: `DB1,INT${offset}`, value: Math.floor(rnd() * 65536) - 32768 };
    case 'REAL':
      // Values exactly representable in float32, so every decoder agrees bit for bit.
      return { type, offset, bit, address: `DB1,REAL${offset}`, value: Math.fround((rnd() - 0.5) * 1e6) };
    case 'BOOL':
      return { type, offset, bit, address: `DB1,X${offset}.${bit}`, value: rnd() < 0.5 };
    case 'STRING': {
      const len = 1 + Math.floor(rnd() * STRING_LENGTH);
      let s = '';
      for (let i = 0; i < len; i++) s += String.fromCharCode(0x41 + Math.floor(rnd() * 26));
      return { type, offset, bit, address: `DB1,S${offset}.${STRING_LENGTH}`, value: s };
    }
  }
  throw new Error(type);
}

/** The DB1 bytes holding every tag's value (BOOLs sharing a byte are merged). */
function image(tags) {
  const db = Buffer.alloc(DB1_SIZE);
  for (const t of tags) {
    switch (t.type) {
      case 'INT':
        db.writeInt16BE(t.value, t.offset);
        break;
      case 'REAL':
        db.writeFloatBE(t.value, t.offset);
        break;
      case 'BOOL':
        if (t.value) db[t.offset] |= 1 << t.bit;
        else db[t.offset] &= ~(1 << t.bit);
        break;
      case 'STRING':
        db[t.offset] = STRING_LENGTH;
        db[t.offset + 1] = t.value.length;
        db.write(t.value, t.offset + 2, 'latin1');
        break;
    }
  }
  return db;
}

const TABLES = [
  { name: '10 scattered', tags: () => scattered(10, 10) },
  { name: '100 scattered', tags: () => scattered(100, 100) },
  { name: '1000 scattered', tags: () => scattered(1000, 1000) },
  { name: '1000 contiguous', tags: () => contiguous(1000, 7) },
];

function table(name) {
  const t = TABLES.find((x) => x.name === name);
  if (!t) throw new Error(`no table ${name}`);
  return t.tags();
}

/** First wrong value in `values` (keyed by address), or undefined when all match. */
function firstMismatch(tags, values) {
  for (const t of tags) {
    const v = values[t.address];
    if (v !== t.value) return `${t.address}: expected ${JSON.stringify(t.value)}, got ${JSON.stringify(v)}`;
  }
  return undefined;
}

module.exports = { TABLES, table, image, firstMismatch, prng, DB1_SIZE, STRING_LENGTH };
