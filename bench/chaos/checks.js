'use strict';
// What must hold after a chaos run (issue #26), measured: one row per check,
// the failures with the PLCs they concern, and those PLCs' fault histories.
const { RECOVERY_MS, TIMEOUT_MS } = require('./plan');
const { ACKED, REJECTED } = require('./clients');

const LOOP_P99_LIMIT_MS = 50;
const HEALTHY_POLLS_MIN = 0.95;
const HEAP_GROWTH_MAX = 0.1;

/**
 * The writes of station `s` against what its PLC applied ([slot, value] in
 * order): every acknowledged write applied exactly once, no write applied
 * twice, nothing applied that was not written, every rejection typed and
 * naming its tag, every slot value read one the PLC applied.
 */
function checkWrites(s, applied, t, fail) {
  const counts = new Map();
  for (const [slot, value] of applied) {
    const n = s.writeOf(value, slot);
    if (n <= 0) fail(s, `the PLC applied ${value} to slot ${slot}, a value never written there`, 'phantom');
    else counts.set(n, (counts.get(n) ?? 0) + 1);
  }
  for (let n = 1; n <= s.seq; n++) {
    const times = counts.get(n) ?? 0;
    const outcome = s.outcome.get(n - 1);
    const what = () => `write ${n} (slot ${s.writeSlot.get(n - 1)} = ${s.p.index * 1_000_000 + n})`;
    t.writes++;
    if (outcome === ACKED) {
      t.acked++;
      if (times === 0) fail(s, `${what()} acknowledged, never applied (lost)`, 'lost');
    } else if (outcome === REJECTED) {
      t.rejected++;
      if (times === 1) t.inDoubt++;
    } else fail(s, `${what()} never settled`, 'lost');
    if (times > 1) fail(s, `${what()} applied ${times} times`, 'twice');
    if (s.seenRead.get(n - 1) && times === 0) fail(s, `${what()}: its value was read, but the PLC never applied it`, 'held');
  }
  for (const [code, n] of Object.entries(s.rejectedCodes)) t.byCode[code] = (t.byCode[code] ?? 0) + n;
  for (const b of s.badRejections) {
    if (!b.typed) fail(s, `write ${b.address} = ${b.value} rejected with an untyped error: ${b.message}`, 'untyped');
    else fail(s, `write ${b.address} = ${b.value} rejected (${b.code}) without naming its tag: ${b.message}`, 'unnamed');
  }
}

/** How long after its fault a link must be back: on a freeport bus a timed-out request also drains the line one more timeout. */
function recoveryMs(s) {
  return RECOVERY_MS + (s.p.driver.protocol === 'freeport' ? TIMEOUT_MS : 0);
}

/**
 * Is a failed item in an otherwise answered poll explained by a fault? The
 * itemError item during an itemError episode; on a freeport bus (one request
 * per station) any item during any episode, as a silent or slow station fails
 * its own items only. `at` is when the answer came: up to two timeouts (the
 * request's and a freeport drain) and slack after the episode ended.
 */
function explained(s, at, item, episodes) {
  const freeport = s.p.driver.protocol === 'freeport';
  return episodes.some(
    (e) => (freeport || (e.fault === 'itemError' && item)) && at >= e.start && at <= (e.end ?? Infinity) + 2 * TIMEOUT_MS + 1500,
  );
}

/** Milliseconds from each ended episode to the first good poll begun after it (0: one was under way); undefined when none. */
function recoveries(s, episodes) {
  return episodes
    .filter((e) => e.end !== undefined)
    .map((e) => {
      const run = s.runs.find(([, last]) => last >= e.end);
      return { e, ms: run ? Math.max(0, run[0] - e.end) : undefined };
    });
}

/** Milliseconds after a certificate fault began from which a good poll can only be one the other certificate answered. */
const SWAP_SLACK_MS = 50;

/**
 * The certificate faults of station `s`: each must be refused (CERTIFICATE_UNTRUSTED, at least once while it
 * lasts), never trusted (no good poll begun while it lasted, nothing written to the PLC with the other
 * certificate). Adds to `c` { episodes, refused, refusals, trusted }.
 */
function checkCertificates(s, episodes, impostorApplied, c, fail) {
  for (const e of episodes.filter((x) => x.fault === 'certificate')) {
    c.episodes++;
    const end = e.end ?? Infinity;
    const refusals = s.refusals.filter((t) => t >= e.start && t <= end + TIMEOUT_MS).length;
    c.refusals += refusals;
    if (refusals > 0) c.refused++;
    else fail(s, `the certificate changed at ${e.start - s.t0} ms, and the client never refused it`, 'certificate');
    if (s.runs.some(([first, last]) => last >= e.start + SWAP_SLACK_MS && first <= end)) {
      c.trusted++;
      fail(
        s,
        `a poll begun while the PLC had another certificate (from ${e.start - s.t0} ms) was answered: trusted silently`,
        'certificate',
      );
    }
  }
  if (impostorApplied.length > 0) {
    c.trusted++;
    fail(s, `${impostorApplied.length} writes applied by the PLC with another certificate: trusted silently`, 'certificate');
  }
}

function evaluate({ o, fleet, stations, status, applied, impostorApplied, connected, loopP99Ms, heap, load, cores, handles }) {
  const failed = [];
  const concerned = new Set();
  const kinds = {};
  const fail = (s, text, kind) => {
    kinds[kind] = (kinds[kind] ?? 0) + 1;
    concerned.add(s.p.index);
    if (kinds[kind] <= 20) failed.push(`PLC ${s.p.index} (${s.p.driver.id}): ${text}`);
  };
  const t = { writes: 0, acked: 0, rejected: 0, inDoubt: 0, byCode: {} };
  let overlapped = 0;
  let wrong = 0;
  let untypedErrors = 0;
  let unexpectedItemErrors = 0;
  let worstRecovery = 0;
  let notBack = 0;
  const healthy = { due: 0, ok: 0 };
  const polls = { due: 0, ok: 0, partial: 0, failed: 0, skipped: 0 };
  const codes = {};
  const certificates = { episodes: 0, refused: 0, refusals: 0, trusted: 0 };
  stations.forEach((s, i) => {
    s.t0 = o.t0;
    checkWrites(s, applied[i], t, fail);
    checkCertificates(s, status.episodes[i], impostorApplied[i], certificates, fail);
    overlapped += s.polls.overlapped;
    if (s.polls.overlapped > 0) fail(s, `${s.polls.overlapped} polls overlapped`, 'overlap');
    for (const k of Object.keys(polls)) polls[k] += s.polls[k];
    if (s.p.healthy) {
      healthy.due += s.healthyPolls.due;
      healthy.ok += s.healthyPolls.ok;
    }
    wrong += s.wrong.length;
    for (const w of s.wrong.slice(0, 3)) fail(s, `wrong value ${w}`, 'values');
    for (const [code, n] of Object.entries(s.errorCodes)) {
      codes[code] = (codes[code] ?? 0) + n;
      if (code.startsWith('untyped')) {
        untypedErrors += n;
        fail(s, `${n} × ${code}`, 'untyped');
      }
    }
    let unexplained = 0;
    for (let k = 0; k < s.failAt.length; k++)
      if (!explained(s, s.failAt.get(k), s.failItem.get(k) === 1, status.episodes[i])) unexplained++;
    if (unexplained > 0) {
      unexpectedItemErrors += unexplained;
      fail(s, `${unexplained} failed items that no fault explains, e.g. ${s.failTexts[0]}`, 'item');
    }
    for (const r of recoveries(s, status.episodes[i])) {
      if (r.ms === undefined || r.ms > recoveryMs(s)) {
        notBack++;
        fail(
          s,
          `no good poll within ${recoveryMs(s)} ms after ${r.e.fault} ended (${r.ms === undefined ? 'none at all' : `${r.ms} ms`})`,
          'recovery',
        );
      } else worstRecovery = Math.max(worstRecovery, r.ms);
    }
    if (status.connections[i] !== 1) fail(s, `${status.connections[i]} connections at the simulator at the end`, 'connections');
    if (connected[i] !== 'connected') fail(s, `link ${connected[i]} at the end`, 'connections');
  });
  const connections = status.connections.reduce((a, b) => a + b, 0);
  const episodes = status.episodes.reduce((a, e) => a + e.length, 0);
  const healthyRatio = healthy.due > 0 ? healthy.ok / healthy.due : 1;
  const heapGrowth = heap.first && heap.last ? heap.last / heap.first - 1 : NaN;
  const rates = o.countsOnly;
  const row = (check, measured, limit, ok, skipped = false) => ({ check, measured: String(measured), limit, ok, skipped });
  /** A figure that depends on the machine's speed: checked unless --counts-only, always with the load beside it. */
  const timed = (check, measured, limit, within, skipped = rates) => ({
    ...row(check, `${measured}, load ${load.highest.toFixed(1)}`, limit, skipped || within, skipped),
    within,
  });
  const rows = [
    row('writes acknowledged, applied exactly once', `${t.acked} of ${t.writes}`, 'lost 0, twice 0', !kinds.lost && !kinds.twice),
    row('writes rejected with a typed error naming it', `${t.rejected}`, 'untyped 0, unnamed 0', !kinds.untyped && !kinds.unnamed),
    row('writes applied that were never written', `${kinds.phantom ?? 0}`, '0', !kinds.phantom),
    row('values read that the PLC did not hold', `${wrong + (kinds.held ?? 0)}`, '0', wrong === 0 && !kinds.held),
    row('item errors no fault explains', `${unexpectedItemErrors}`, '0', unexpectedItemErrors === 0),
    row('errors that are not PlcError', `${untypedErrors}`, '0', untypedErrors === 0),
    row('overlapping polls', `${overlapped}`, '0', overlapped === 0),
    row(
      'links back within backoff after a fault',
      `${episodes - notBack} of ${episodes}, worst ${worstRecovery} ms`,
      `≤ ${RECOVERY_MS} ms (freeport ${RECOVERY_MS + TIMEOUT_MS})`,
      notBack === 0,
    ),
    row(
      'certificates changed: refused, never trusted',
      `${certificates.refused} of ${certificates.episodes} refused (${certificates.refusals} refusals), trusted ${certificates.trusted}`,
      'all refused, trusted 0',
      !kinds.certificate,
    ),
    row('connections at the simulators at the end', `${connections}`, `${o.plcs}`, connections === o.plcs && !kinds.connections),
    row(
      'handles left behind',
      handles.after === handles.before ? 'none' : `before: ${handles.before}; after: ${handles.after}`,
      'none',
      handles.after === handles.before,
    ),
    timed(
      'polls achieved / due, healthy PLCs',
      `${(healthyRatio * 100).toFixed(1)} % (${healthy.ok}/${healthy.due})`,
      `≥ ${HEALTHY_POLLS_MIN * 100} %`,
      healthyRatio >= HEALTHY_POLLS_MIN,
    ),
    timed('event-loop delay p99', `${loopP99Ms.toFixed(1)} ms`, `< ${LOOP_P99_LIMIT_MS} ms`, loopP99Ms < LOOP_P99_LIMIT_MS),
    timed(
      'heap after GC vs first minute',
      Number.isNaN(heapGrowth)
        ? 'not measured'
        : `${heapGrowth >= 0 ? '+' : ''}${(heapGrowth * 100).toFixed(1)} % (${(heap.last / 2 ** 20).toFixed(1)} MiB)`,
      `≤ +${HEAP_GROWTH_MAX * 100} %`,
      Number.isNaN(heapGrowth) || heapGrowth <= HEAP_GROWTH_MAX,
      rates || Number.isNaN(heapGrowth),
    ),
  ];
  for (const r of rows) if (!r.ok && !r.skipped && !failed.some((f) => f.startsWith(r.check))) failed.push(`${r.check}: ${r.measured}`);
  const byFault = {};
  for (const p of fleet) for (const e of p.schedule) byFault[e.fault] = (byFault[e.fault] ?? 0) + 1;
  const figures = [
    `seed ${o.seed}; ${fleet.filter((p) => p.healthy).length} of ${fleet.length} PLCs without faults; ${episodes} fault episodes: ${Object.entries(
      byFault,
    )
      .map(([f, n]) => `${f} ${n}`)
      .join(', ')}`,
    `polls: ${polls.due} due, ${polls.ok} good, ${polls.partial} with item errors, ${polls.failed} failed, ${polls.skipped} skipped (previous still running)`,
    `writes: ${t.writes}, ${t.acked} acknowledged, ${t.rejected} rejected (${Object.entries(t.byCode)
      .map(([c, n]) => `${c} ${n}`)
      .join(', ')}), of those ${t.inDoubt} applied by the PLC (answer lost: in doubt, reported as failed)`,
    `load average (1 min) on ${cores} cores: ${load.start.toFixed(1)} at the start, ${load.highest.toFixed(1)} at the highest, ${load.end.toFixed(1)} at the end`,
    `poll and item errors: ${Object.entries(codes)
      .map(([c, n]) => `${c} ${n}`)
      .join(', ')}`,
  ];
  const histories = [...concerned].slice(0, 10).map((i) => {
    const p = fleet[i];
    const lines = status.episodes[i].map(
      (e) => `    ${e.fault} at ${e.start - o.t0} ms, ended at ${e.end === undefined ? '(not ended)' : `${e.end - o.t0} ms`}`,
    );
    return `  PLC ${i} (${p.driver.id}) fault history:\n${lines.join('\n') || '    (none)'}`;
  });
  return { o, rows, failed, histories, figures, totals: t, kinds };
}

module.exports = { evaluate };
