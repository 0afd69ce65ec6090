/**
 * test/support/pack.ts, how the install and packaging tests pack the
 * package: no script of the package runs, with the npm `npm test` finds first
 * on its PATH (the npm 10 node-red brings into node_modules/.bin, which runs
 * `prepare` in `npm pack` even with --ignore-scripts) as with the system's.
 */
import { expect } from 'chai';
import * as fs from 'node:fs';
import * as os from 'node:os';
import * as path from 'node:path';
import { packTarball, ROOT } from './support/pack';

describe('packTarball: the tarball without running the package scripts', function () {
  this.timeout(120_000);
  const dirs: string[] = [];
  after(() => dirs.forEach((d) => fs.rmSync(d, { recursive: true, force: true })));

  const NPMS = [
    {
      name: "the npm first on npm test's PATH (node_modules/.bin)",
      path: `${path.join(ROOT, 'node_modules/.bin')}${path.delimiter}${process.env.PATH}`,
    },
    {
      name: "the system's npm",
      path: (process.env.PATH ?? '')
        .split(path.delimiter)
        .filter((d) => !d.includes('node_modules'))
        .join(path.delimiter),
    },
  ];
  for (const npm of NPMS) {
    it(`runs no prepare, prepack or postpack with ${npm.name}`, () => {
      const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-pack-'));
      dirs.push(dir);
      const mark = `node -e "require('fs').writeFileSync('ran-' + process.env.npm_lifecycle_event, '')"`;
      fs.writeFileSync(
        path.join(dir, 'package.json'),
        JSON.stringify({
          name: 'pack-probe',
          version: '1.0.0',
          files: ['index.js'],
          scripts: { prepare: mark, prepack: mark, postpack: mark },
        }),
      );
      fs.writeFileSync(path.join(dir, 'index.js'), 'module.exports = 1;\n');
      const into = fs.mkdtempSync(path.join(os.tmpdir(), 'plcwire-packed-'));
      dirs.push(into);
      const saved = process.env.PATH;
      process.env.PATH = npm.path;
      let tarball: string;
      try {
        tarball = packTarball(into, dir);
      } finally {
        process.env.PATH = saved;
      }
      expect(fs.readdirSync(dir).filter((f) => f.startsWith('ran-'))).to.deep.equal([]);
      expect(tarball).to.equal(path.join(into, 'pack-probe-1.0.0.tgz'));
      expect(fs.readdirSync(into)).to.deep.equal(['pack-probe-1.0.0.tgz']);
    });
  }
});
