'use strict';
// The program of the S7CommPlus benchmark: the 100 tags of the "100
// scattered" table (bench/lib/tables.js: the same types and values) as the
// members of two data blocks, "Bench" with optimized access (read by name
// only, over S7CommPlus) and "Std" with standard access (the same members at
// addresses, readable over s7:// and s7plus://). The values are the members'
// start values, so each client's first poll is checked against them.
const { table, STRING_LENGTH } = require('./tables');

const TABLE = '100 scattered';
const OPTIMIZED_DB = { name: 'Bench', number: 2 };
const STANDARD_DB = { name: 'Std', number: 1 };

const IEC = { INT: 'Int', REAL: 'Real', BOOL: 'Bool', STRING: `String[${STRING_LENGTH}]` };

/** A start value as the source writes it. */
function literal(t) {
  switch (t.type) {
    case 'INT':
      return String(t.value);
    case 'REAL':
      // Exactly representable in float32: the shortest text that reads back to the same float32.
      return Number.isInteger(t.value) ? `${t.value}.0` : String(t.value);
    case 'BOOL':
      return t.value ? 'TRUE' : 'FALSE';
    case 'STRING':
      return `'${t.value}'`;
  }
  throw new Error(t.type);
}

/** The benchmark's members: name (T000 …), type, value. */
function members() {
  return table(TABLE).map((t, i) => ({ member: `T${String(i).padStart(3, '0')}`, type: t.type, value: t.value }));
}

function dbSource(db, optimized) {
  const lines = members().map((m) => `      ${m.member} : ${IEC[m.type]} := ${literal(m)};`);
  return [
    `DATA_BLOCK "${db.name}"`,
    `{ S7_Optimized_Access := '${optimized ? 'TRUE' : 'FALSE'}' }`,
    'VERSION : 0.1',
    'NON_RETAIN',
    '   STRUCT',
    ...lines,
    '   END_STRUCT;',
    'BEGIN',
    'END_DATA_BLOCK',
    '',
  ].join('\n');
}

/** The sources and block numbers the simulator is started with (S7PlusService options). */
function program() {
  return {
    sources: [
      { name: `${OPTIMIZED_DB.name}.db`, content: dbSource(OPTIMIZED_DB, true) },
      { name: `${STANDARD_DB.name}.db`, content: dbSource(STANDARD_DB, false) },
    ],
    db: { [OPTIMIZED_DB.name]: OPTIMIZED_DB.number, [STANDARD_DB.name]: STANDARD_DB.number },
  };
}

/** The optimized block's tags by name: ours ('"Bench".T000') and the s7commplus package's ('Bench.T000'). */
function optimizedNames() {
  return members().map((m) => ({
    name: `"${OPTIMIZED_DB.name}".${m.member}`,
    python: `${OPTIMIZED_DB.name}.${m.member}`,
    type: m.type,
    value: m.value,
  }));
}

/** The standard block's tags by address, from the compiled table of the same sources (`compileSymbols` of our library). */
function standardAddresses(compileSymbols) {
  const { sources, db } = program();
  const compiled = compileSymbols(sources, { db });
  return members().map((m) => {
    const entry = compiled.lookup(`"${STANDARD_DB.name}".${m.member}`);
    if (!entry || !entry.address) throw new Error(`no address for "${STANDARD_DB.name}".${m.member}`);
    return { name: entry.address, type: m.type, value: m.value };
  });
}

/** The first value of `values` (keyed by each tag's `key`) that is not the tag's, or undefined. */
function firstWrong(tags, values, key = 'name') {
  for (const t of tags) {
    const v = values[t[key]];
    if (v !== t.value) return `${t[key]}: expected ${JSON.stringify(t.value)}, got ${JSON.stringify(v)}`;
  }
  return undefined;
}

module.exports = { program, optimizedNames, standardAddresses, firstWrong, OPTIMIZED_DB, STANDARD_DB };
