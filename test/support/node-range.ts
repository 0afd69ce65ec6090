/**
 * Whether an `engines.node` range admits a Node version, for the forms the
 * packages of package-lock.json use: `||` alternatives of space-separated
 * comparators (`>=`, `>`, `<=`, `<`, `=`, `^`, `~`, with or without a space
 * after the operator), partial versions and x-ranges (`20`, `6.*`, `>= 10.x`)
 * and `*`. Semantics as npm's semver (https://github.com/npm/node-semver#ranges);
 * prereleases do not occur in these ranges and are not handled. Throws on any
 * other form, so a range it cannot read is never passed silently.
 */
type Version = [number, number, number];

function compare(a: Version, b: Version): number {
  for (let i = 0; i < 3; i++) if (a[i] !== b[i]) return a[i]! - b[i]!;
  return 0;
}

function parseVersion(version: string): Version {
  const m = /^v?(\d+)\.(\d+)\.(\d+)$/.exec(version);
  if (!m) throw new Error(`not a Node version: "${version}"`);
  return [Number(m[1]), Number(m[2]), Number(m[3])];
}

/** One comparator as a half-open interval [low, high): either end may be missing. */
function interval(op: string, partial: string, range: string): { low?: Version; lowOpen?: boolean; high?: Version; highClosed?: boolean } {
  const m = /^(\d+|[xX*])(?:\.(\d+|[xX*]))?(?:\.(\d+|[xX*]))?$/.exec(partial);
  if (!m) throw new Error(`unsupported engines range "${range}" (at "${partial}")`);
  const parts = [m[1], m[2], m[3]].map((p) => (p === undefined || /^[xX*]$/.test(p) ? undefined : Number(p)));
  const given = parts.findIndex((p) => p === undefined);
  const known = given === -1 ? 3 : given; // how many leading numbers are given
  const low: Version = [parts[0] ?? 0, known > 1 ? parts[1]! : 0, known > 2 ? parts[2]! : 0];
  // The first version past the partial one: 20 → 21.0.0, 6.1 → 6.2.0.
  const next = (): Version | undefined =>
    known === 0 ? undefined : known === 1 ? [low[0] + 1, 0, 0] : known === 2 ? [low[0], low[1] + 1, 0] : undefined;
  switch (op) {
    case '':
    case '=':
      return known === 3 ? { low, high: low, highClosed: true } : { low: known ? low : undefined, high: next() };
    case '>=':
      return { low };
    case '>':
      return known === 3 ? { low, lowOpen: true } : { low: next() };
    case '<':
      return { high: low };
    case '<=':
      return known === 3 ? { high: low, highClosed: true } : { high: next() };
    case '~':
      return { low, high: known === 1 ? [low[0] + 1, 0, 0] : [low[0], low[1] + 1, 0] };
    case '^':
      return {
        low,
        high: low[0] > 0 || known === 1 ? [low[0] + 1, 0, 0] : low[1] > 0 || known === 2 ? [0, low[1] + 1, 0] : [0, 0, low[2] + 1],
      };
    default:
      throw new Error(`unsupported engines range "${range}" (operator "${op}")`);
  }
}

export function admitsNode(range: string, version: string): boolean {
  const v = parseVersion(version);
  return range.split('||').some((alternative) => {
    const comparators = [...alternative.trim().matchAll(/(>=|<=|>|<|=|\^|~)?\s*([^\s<>=^~]+)/g)];
    if (
      alternative.trim() === '' ||
      comparators
        .map((c) => c[0])
        .join('')
        .replace(/\s/g, '') !== alternative.replace(/\s/g, '')
    )
      throw new Error(`unsupported engines range "${range}"`);
    return comparators.every(([, op, partial]) => {
      const { low, lowOpen, high, highClosed } = interval(op ?? '', partial!, range);
      if (low && (lowOpen ? compare(v, low) <= 0 : compare(v, low) < 0)) return false;
      if (high && (highClosed ? compare(v, high) > 0 : compare(v, high) >= 0)) return false;
      return true;
    });
  });
}
