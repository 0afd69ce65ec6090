#!/usr/bin/env node
'use strict';
// Installs the test-only peers that live outside the package's own
// dependencies when they are missing, so `npm install && npm test` works on a
// fresh clone and runs what `.ci/run` runs (and `npm run bench` finds its anchors):
//   interop: node-snap7 (snap7 built from source), nodes7, @st-one-io/nodes7,
//            node-red-contrib-s7 (the Node-RED benchmark's incumbent)
//   nr5:     Node 22 and Node-RED 5
//   awlsim:  awlsim AWLSIM_VERSION, pure Python, in the venv test/interop/.venv,
//            for the layout comparison of test/symbols-awlsim.test.ts
//   s7commplus: the s7commplus package S7COMMPLUS_VERSION (PyPI, MIT, pure
//            Python with the cryptography wheel), in a venv of its own,
//            test/interop/.venv-s7commplus, so awlsim's venv is never touched:
//            the independent S7CommPlus client and server of test/interop/s7commplus/
//   plc4x:   Apache PLC4X PLC4X_VERSION (plc4j-api, plc4j-driver-s7 and their
//            dependencies from Maven Central with mvn, into test/interop/plc4x/lib),
//            and test/interop/plc4x/Plc4xPeer.java compiled with javac (Java 17),
//            for test/plc4x-interop.test.ts
//   tahu:    Eclipse Tahu TAHU_VERSION (tahu-core, the Sparkplug reference
//            implementation) and the jars it needs, listed in
//            test/interop/tahu/pom.xml because Tahu's parent POM is not on Maven
//            Central, into test/interop/tahu/lib, and TahuHost.java compiled with
//            javac: the independent Sparkplug B host of test/sparkplug-tahu.test.ts
// Usage: node test/support/install-peers.js interop [nr5] [awlsim] [s7commplus] [plc4x] [tahu]
// Already installed: does nothing (no network). A peer that cannot be installed
// (no network, no python3) is not fatal: the rest still runs, and the tests that
// need it fail or skip saying so.
const { spawnSync } = require('node:child_process');
const fs = require('node:fs');
const path = require('node:path');

const ROOT = path.resolve(__dirname, '../..');
/** The awlsim whose layout differences test/symbols-awlsim.test.ts knows. */
const AWLSIM_VERSION = '0.77.1';
/** The s7commplus whose client and server emulator test/interop/s7commplus/ drives. */
const S7COMMPLUS_VERSION = '0.3.0';
/** The Apache PLC4X whose S7 driver test/interop/plc4x/ drives (its pom.xml names the same). */
const PLC4X_VERSION = '0.13.1';
const PLC4X_DIR = 'test/interop/plc4x';
/** The Eclipse Tahu whose decoder test/interop/tahu/TahuHost.java drives. */
const TAHU_VERSION = '1.0.21';
const TAHU_DIR = 'test/interop/tahu';

const PYTHON_PEERS = {
  awlsim: {
    name: 'awlsim',
    version: AWLSIM_VERSION,
    pip: 'awlsim',
    venv: 'test/interop/.venv',
    probe: 'from awlsim_loader.common import VERSION_STRING; print(VERSION_STRING)',
    // Pure Python (no Cython build: a few seconds).
    env: { AWLSIM_CYTHON_BUILD: '0' },
    skip: 'test/symbols-awlsim.test.ts will skip',
  },
  s7commplus: {
    name: 's7commplus',
    version: S7COMMPLUS_VERSION,
    pip: 's7commplus',
    venv: 'test/interop/.venv-s7commplus',
    // Importing the package proves its dependency (cryptography) loads too.
    probe: 'import importlib.metadata as m, s7commplus; print(m.version("s7commplus"))',
    skip: 'the tests against the s7commplus peer (test/support/s7commplus-peer.ts) will skip',
  },
};

const NPM_PEERS = {
  interop: {
    dir: 'test/interop',
    has: ['node-snap7', 'nodes7', '@st-one-io/nodes7', 'node-red-contrib-s7'].map((p) => `node_modules/${p}/package.json`),
  },
  nr5: { dir: 'test/nr5', has: ['node_modules/node/bin/node', 'node_modules/node-red/package.json'] },
};
const SETS = [...Object.keys(NPM_PEERS), ...Object.keys(PYTHON_PEERS), 'plc4x', 'tahu'];

function installNpmPeer(peer) {
  const cwd = path.join(ROOT, peer.dir);
  const missing = peer.has.filter((f) => !fs.existsSync(path.join(cwd, f)));
  if (missing.length === 0) return;
  console.log(`Installing ${peer.dir} (missing: ${missing.join(', ')})`);
  // Under `npm run`, npm_execpath is npm's own CLI: run it with this Node.
  const npm = process.env.npm_execpath;
  const r = npm
    ? spawnSync(process.execPath, [npm, 'ci', '--no-audit', '--no-fund'], { cwd, stdio: 'inherit' })
    : spawnSync('npm', ['ci', '--no-audit', '--no-fund'], { cwd, stdio: 'inherit', shell: process.platform === 'win32' });
  if (r.status !== 0) console.warn(`Could not install ${peer.dir} (npm ci exited ${r.status ?? r.signal}).`);
}

/** The venv's Python of `venv` (an absolute path). */
function venvPython(venv) {
  return path.join(venv, process.platform === 'win32' ? 'Scripts/python.exe' : 'bin/python');
}

/** The version `python` reports with `probe` (a Python one-liner that prints it), or undefined (no such Python, no package). */
function probeVersion(python, probe) {
  const r = spawnSync(python, ['-c', probe], { encoding: 'utf8', timeout: 30_000 });
  return r.status === 0 ? r.stdout.trim() : undefined;
}

/**
 * Installs `peer.pip` into the venv `peer.venv` unless its Python already
 * reports `peer.version`. Not fatal: without python3 or PyPI it warns what
 * will skip, and leaves no half-made venv behind.
 */
function installPythonPeer(peer) {
  const venv = path.join(ROOT, peer.venv);
  const python = venvPython(venv);
  const found = fs.existsSync(python) ? probeVersion(python, peer.probe) : undefined;
  if (found === peer.version) return;
  const what = `${peer.name} ${peer.version}`;
  const py3 = spawnSync('python3', ['--version'], { encoding: 'utf8', timeout: 30_000 });
  if (py3.status !== 0) {
    console.warn(`${what} not installed: no python3 (${py3.error?.code ?? `exit ${py3.status}`}); ${peer.skip}.`);
    return;
  }
  console.log(`Installing ${what} into ${peer.venv} (${found ? `it has ${peer.name} ${found}` : 'missing'})`);
  fs.rmSync(venv, { recursive: true, force: true });
  const run = (cmd, args, env) => spawnSync(cmd, args, { cwd: ROOT, stdio: 'inherit', env: { ...process.env, ...env } });
  const made = run('python3', ['-m', 'venv', venv]);
  // A short network timeout, so no PyPI fails fast.
  const pip =
    made.status === 0 &&
    run(
      python,
      ['-m', 'pip', 'install', '-q', '--disable-pip-version-check', '--timeout', '20', '--retries', '1', `${peer.pip}==${peer.version}`],
      peer.env,
    );
  if (!pip || pip.status !== 0 || probeVersion(python, peer.probe) !== peer.version) {
    fs.rmSync(venv, { recursive: true, force: true });
    console.warn(`${what} not installed (${made.status !== 0 ? 'python3 -m venv' : 'pip install'} failed); ${peer.skip}.`);
  }
}

/** The files a built PLC4X peer has: the driver's jar and the compiled program, newer than its source. */
function plc4xBuilt() {
  const dir = path.join(ROOT, PLC4X_DIR);
  const jar = path.join(dir, 'lib', `plc4j-driver-s7-${PLC4X_VERSION}.jar`);
  const cls = path.join(dir, 'build', 'Plc4xPeer.class');
  if (!fs.existsSync(jar) || !fs.existsSync(cls)) return false;
  return fs.statSync(cls).mtimeMs >= fs.statSync(path.join(dir, 'Plc4xPeer.java')).mtimeMs;
}

/** Why a Java peer cannot be built here (a missing tool), or undefined. */
function javaMissingTool() {
  for (const [tool, args] of [
    ['java', ['-version']],
    ['javac', ['-version']],
    ['mvn', ['-v']],
  ]) {
    const r = spawnSync(tool, args, { encoding: 'utf8', timeout: 60_000 });
    if (r.status !== 0) return `no ${tool} (${r.error?.code ?? `exit ${r.status}`})`;
  }
  return undefined;
}

/**
 * Fetches PLC4X's jars with mvn and compiles the peer with javac, unless both
 * are there. Not fatal: without java, javac, mvn or Maven Central it warns
 * that test/plc4x-interop.test.ts will skip, and says why.
 */
function installPlc4x() {
  if (plc4xBuilt()) return;
  const skip = 'test/plc4x-interop.test.ts will skip';
  const missing = javaMissingTool();
  if (missing) {
    console.warn(`Apache PLC4X ${PLC4X_VERSION} peer not built: ${missing}; ${skip}.`);
    return;
  }
  console.log(`Building the Apache PLC4X ${PLC4X_VERSION} peer in ${PLC4X_DIR}`);
  const cwd = path.join(ROOT, PLC4X_DIR);
  const mvn = spawnSync(
    'mvn',
    ['-q', '-B', '-Dstyle.color=never', 'dependency:copy-dependencies', '-DoutputDirectory=lib', '-DincludeScope=runtime'],
    {
      cwd,
      stdio: 'inherit',
      timeout: 900_000,
    },
  );
  if (mvn.status !== 0) {
    console.warn(`Apache PLC4X ${PLC4X_VERSION} jars not fetched (mvn exited ${mvn.status ?? mvn.signal}); ${skip}.`);
    return;
  }
  const javac = spawnSync('javac', ['-d', 'build', '-cp', `lib${path.sep}*`, 'Plc4xPeer.java'], {
    cwd,
    stdio: 'inherit',
    timeout: 300_000,
  });
  if (javac.status !== 0) console.warn(`Plc4xPeer.java did not compile (javac exited ${javac.status ?? javac.signal}); ${skip}.`);
}

/** The files a built Tahu host has: Tahu's jar and the compiled program, newer than its source. */
function tahuBuilt() {
  const dir = path.join(ROOT, TAHU_DIR);
  const jar = path.join(dir, 'lib', `tahu-core-${TAHU_VERSION}.jar`);
  const cls = path.join(dir, 'build', 'TahuHost.class');
  if (!fs.existsSync(jar) || !fs.existsSync(cls)) return false;
  return fs.statSync(cls).mtimeMs >= fs.statSync(path.join(dir, 'TahuHost.java')).mtimeMs;
}

/**
 * Fetches Tahu's jars with mvn (tahu-core alone, `-Dtransitive=false`, since its
 * parent POM is not on Maven Central; the jars it needs from our pom.xml) and
 * compiles the host with javac, unless both are there. Not fatal here: without
 * java, javac, mvn or Maven Central it warns that test/sparkplug-tahu.test.ts
 * will skip and why (.ci/run makes the missing peer fatal).
 */
function installTahu() {
  if (tahuBuilt()) return true;
  const skip = 'test/sparkplug-tahu.test.ts will skip';
  const missing = javaMissingTool();
  if (missing) {
    console.warn(`Eclipse Tahu ${TAHU_VERSION} host not built: ${missing}; ${skip}.`);
    return false;
  }
  console.log(`Building the Eclipse Tahu ${TAHU_VERSION} host in ${TAHU_DIR}`);
  const cwd = path.join(ROOT, TAHU_DIR);
  const mvn = (args) => spawnSync('mvn', ['-q', '-B', '-Dstyle.color=never', ...args], { cwd, stdio: 'inherit', timeout: 900_000 });
  const deps = mvn(['dependency:copy-dependencies', '-DoutputDirectory=lib', '-DincludeScope=runtime']);
  const core =
    deps.status === 0 &&
    mvn(['dependency:copy', `-Dartifact=org.eclipse.tahu:tahu-core:${TAHU_VERSION}`, '-Dtransitive=false', '-DoutputDirectory=lib']);
  if (deps.status !== 0 || !core || core.status !== 0) {
    const r = deps.status !== 0 ? deps : core;
    console.warn(`Eclipse Tahu ${TAHU_VERSION} jars not fetched (mvn exited ${r.status ?? r.signal}); ${skip}.`);
    return false;
  }
  const javac = spawnSync('javac', ['-d', 'build', '-cp', `lib${path.sep}*`, 'TahuHost.java'], {
    cwd,
    stdio: 'inherit',
    timeout: 300_000,
  });
  if (javac.status !== 0) {
    console.warn(`TahuHost.java did not compile (javac exited ${javac.status ?? javac.signal}); ${skip}.`);
    return false;
  }
  return true;
}

if (require.main === module) {
  for (const name of process.argv.slice(2).filter((a) => a !== '--require')) {
    if (!SETS.includes(name)) throw new Error(`install-peers: unknown set "${name}" (${SETS.join(', ')})`);
    if (name === 'plc4x') installPlc4x();
    else if (name === 'tahu') {
      // --require (.ci/run): a host that cannot be built fails the run, never a silent skip.
      if (!installTahu() && process.argv.includes('--require')) process.exitCode = 1;
    } else if (PYTHON_PEERS[name]) installPythonPeer(PYTHON_PEERS[name]);
    else installNpmPeer(NPM_PEERS[name]);
  }
}

module.exports = { AWLSIM_VERSION, S7COMMPLUS_VERSION, PLC4X_VERSION, PLC4X_DIR, plc4xBuilt, TAHU_VERSION, TAHU_DIR, tahuBuilt };
