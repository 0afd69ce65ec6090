/**
 * `npm run lint` inside `npm test`: ESLint (eslint.config.mjs) finds no
 * problem and every file prettier covers is formatted as `npm run format`
 * leaves it. A failure lists the files and, for ESLint, each message.
 */
import { expect } from 'chai';
import { execFile } from 'node:child_process';
import * as path from 'node:path';
import { ESLint } from 'eslint';
import { ROOT } from './support/pack';

describe('lint', function () {
  // Type-aware ESLint loads the whole TypeScript program: ~15-30 s on two quiet cores, over 3 minutes beside
  // seven other builds (load 15): a deadline for a hung linter, not a speed test.
  this.timeout(600_000);

  it('ESLint reports no problem in lib, test, bench, nodes, demo and bin', async () => {
    const eslint = new ESLint({ cwd: ROOT });
    const results = await eslint.lintFiles(['.']);
    const problems = results
      .filter((r) => r.messages.length > 0)
      .flatMap((r) =>
        r.messages.map((m) => `${path.relative(ROOT, r.filePath)}:${m.line ?? 0}:${m.column ?? 0} ${m.ruleId ?? 'parse'}: ${m.message}`),
      );
    expect(results.length, 'files linted').to.be.greaterThan(100);
    if (problems.length > 0) expect.fail(`ESLint (npx eslint .) found ${problems.length} problems:\n${problems.join('\n')}`);
  });

  it('every file prettier covers is formatted (npm run format fixes them)', async () => {
    const bin = require.resolve('prettier/bin/prettier.cjs', { paths: [ROOT] });
    // --list-different prints the unformatted files, one a line, and exits 1 when there are any.
    const out = await new Promise<{ code: number; stdout: string; stderr: string }>((resolve) => {
      execFile(process.execPath, [bin, '--list-different', '.'], { cwd: ROOT, encoding: 'utf8' }, (err, stdout, stderr) => {
        const code = err ? (typeof err.code === 'number' ? err.code : -1) : 0;
        resolve({ code, stdout, stderr });
      });
    });
    expect(out.stderr, 'prettier errors').to.equal('');
    const files = out.stdout.split('\n').filter((l) => l !== '');
    if (files.length > 0)
      expect.fail(`${files.length} files not formatted as prettier would (npm run format fixes them):\n${files.join('\n')}`);
    expect(out.code, 'prettier exit code').to.equal(0);
  });
});
