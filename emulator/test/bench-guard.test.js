// The headline figures of BENCHMARKS.md, guarded: the firmware's and the benchmark firmware's
// cycles and latencies, with the XIP cache modelled (src/gaps/xip-cache.js), measured on a few
// poses (src/bench/headline.js, `GUARD_SIZES`) and compared with the committed table
// (emulator/bench-guard.json). Emulated cycles are the same on every run, so any change is the
// code's: a figure more than the table's tolerance (3 %) above its committed value fails.
// When a change is meant (or a figure improved), `./dev bench --update-guard` rewrites the
// table; commit it with the change.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { measureLockStep } from '../src/bench/firmware-bench.js';
import {
  compareWithGuard,
  guardPoses,
  HEADLINES,
  measureHeadlines,
  pathPoses,
  readGuard,
} from '../src/bench/headline.js';
import { setXipCacheByDefault, xipCacheByDefault } from '../src/gaps/index.js';

test('no headline figure is more than 3 % above the committed table (XIP cache modelled)', () => {
  const table = readGuard();
  assert.ok(table, 'emulator/bench-guard.json is missing: ./dev bench --update-guard');
  assert.deepEqual(Object.keys(table.figures).sort(), Object.keys(HEADLINES).sort());
  const modelled = xipCacheByDefault();
  setXipCacheByDefault(true); // even under HEXAPOD_XIP_CACHE=off: the table is the model's
  let figures;
  try {
    ({ figures } = measureHeadlines(guardPoses(), table.sizes));
  } finally {
    setXipCacheByDefault(modelled);
  }
  const { regressions, improvements } = compareWithGuard(figures, table);
  for (const { name, was, now } of improvements) {
    console.log(`# improved: ${name} ${was} -> ${now} (./dev bench --update-guard to keep it)`);
  }
  assert.deepEqual(
    regressions.map(
      ({ name, was, now, ratio }) => `${name}: ${was} -> ${now} (x${ratio.toFixed(3)})`,
    ),
    [],
    'headline figures regressed (./dev bench --update-guard if the change is meant)',
  );
  // The targets themselves (issue 23, BENCHMARKS.md), whatever the table says: within its
  // tolerance a figure could creep past one.
  const over = Object.entries(TARGETS)
    .filter(([name, bound]) => !(figures[name] <= bound))
    .map(([name, bound]) => `${name} ${figures[name]} > ${bound}`);
  assert.deepEqual(over, [], 'headline figures past their targets');
});

/** Upper bounds of the issue-23 targets, for the figures the guard's samples measure as the bench does. */
const TARGETS = {
  ikCycles: 8000,
  trackerFrameCycles: 15000,
  frameLatencyMaxUs: 200,
  poseLatencyMaxUs: 500,
  longestPassCycles: 125000,
};

test('a pose line costs at most 30,000 CPU cycles (200 lines lock-step, as BENCHMARKS.md measures)', () => {
  const modelled = xipCacheByDefault();
  setXipCacheByDefault(true);
  let result;
  try {
    result = measureLockStep(pathPoses(200).map((p) => `pose ${p}`));
  } finally {
    setXipCacheByDefault(modelled);
  }
  assert.equal(result.ok, 200);
  assert.ok(result.cyclesPerLine <= 30000, `${result.cyclesPerLine.toFixed(1)} cycles a line`);
});

test('the guard compares as it says: more than the tolerance above fails, below does not', () => {
  const table = { tolerance: 0.03, figures: { a: 100, b: 100, c: 100 } };
  const { regressions, improvements } = compareWithGuard({ a: 103, b: 103.5, c: 96 }, table);
  assert.deepEqual(
    regressions.map((r) => r.name),
    ['b'],
  );
  assert.deepEqual(
    improvements.map((r) => r.name),
    ['c'],
  );
});
