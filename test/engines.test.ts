/**
 * The Node versions the README promises, held to what npm installs: every
 * package of package-lock.json whose `engines.node` does not admit a Node
 * makes `npm install` on that Node warn EBADENGINE (and, with
 * engine-strict, fail).
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as path from 'node:path';
import { admitsNode } from './support/node-range';

const ROOT = path.resolve(__dirname, '../..');

interface LockPackage {
  dev?: boolean;
  devOptional?: boolean;
  optional?: boolean;
  os?: string[];
  cpu?: string[];
  engines?: { node?: string } | string[];
}
const lock = JSON.parse(fs.readFileSync(path.join(ROOT, 'package-lock.json'), 'utf8')) as { packages: Record<string, LockPackage> };
const pkg = JSON.parse(fs.readFileSync(path.join(ROOT, 'package.json'), 'utf8')) as { engines: { node: string } };

/** The packages of the lock (name and range) whose engines.node does not admit `version`. */
function refusing(version: string, which: (p: LockPackage) => boolean): string[] {
  return Object.entries(lock.packages)
    .filter(([key, p]) => key !== '' && which(p) && !Array.isArray(p.engines) && p.engines?.node !== undefined)
    .filter(([, p]) => !admitsNode((p.engines as { node: string }).node, version))
    .map(([key, p]) => `${key.replace(/^node_modules\//, '')} (${(p.engines as { node: string }).node})`);
}

describe('engines: the Node versions the README names, for what npm installs', () => {
  it("reads every engines.node range of the lock (a range it cannot read would be no check at all), as npm's semver does", () => {
    for (const p of Object.values(lock.packages)) if (!Array.isArray(p.engines) && p.engines?.node) admitsNode(p.engines.node, '20.0.0');
    const cases: [string, string, boolean][] = [
      ['^22.17.0 || >=24.0.0', '20.19.0', false],
      ['^22.17.0 || >=24.0.0', '22.17.0', true],
      ['^22.17.0 || >=24.0.0', '23.0.0', false],
      ['^20.19.0 || ^22.13.0 || >=24', '20.19.0', true],
      ['^20.19.0 || ^22.13.0 || >=24', '22.12.0', false],
      ['18 || 20 || >=22', '20.5.1', true],
      ['18 || 20 || >=22', '21.7.3', false],
      ['>=16 || 14 >=14.17', '14.16.0', false],
      ['>=16 || 14 >=14.17', '14.17.0', true],
      ['6.* || 8.* || >= 10.*', '9.0.0', false],
      ['>= 10.x', '10.0.0', true],
      ['>=20.11.0', '20.10.9', false],
      ['*', '0.0.1', true],
    ];
    expect(cases.map(([range, version]) => [range, version, admitsNode(range, version)])).to.deep.equal(cases);
    expect(() => admitsNode('>=20.0.0-rc.1', '20.0.0')).to.throw(/unsupported engines range ">=20\.0\.0-rc\.1"/);
  });

  it('the runtime dependencies admit the oldest Node the engines field admits (Node 20.0.0: the README says Node.js ≥ 20)', () => {
    expect(pkg.engines.node).to.equal('>=20');
    expect(refusing('20.0.0', (p) => !p.dev && !p.devOptional)).to.deep.equal([]);
  });

  it('every package of a development install admits Node 20.19.0 and the Node running this, so npm install warns no EBADENGINE', () => {
    // 20.19.0, not 20.0.0: eslint 10 and its parts need it (the README says so).
    for (const version of ['20.19.0', process.versions.node])
      expect(
        refusing(version, () => true),
        `on Node ${version}`,
      ).to.deep.equal([]);
    expect(fs.readFileSync(path.join(ROOT, 'README.md'), 'utf8')).to.include('Node.js ≥ 20.19');
  });
});
