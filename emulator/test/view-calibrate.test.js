// The page's guided calibration (emulator/view/calibrate.js) in headless Chromium against the
// real firmware through `./dev run`'s view: servo by servo the arm stepped with the panel's
// buttons and taken as level, the five check poses passed, `save`; then `config`, typed on the
// page, lists the trims (worked out here from eq. 13 / 14, W = W0 + d r (alpha - alpha0), with
// the board's own listings), saved, and a power cycle brings them back. Quitting midway first
// leaves `config` as it was.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { expectedTrim, servosFromListings } from '../src/test-support/e2e-support.js';
import {
  openPage,
  skipWithoutChromium,
  startRunner,
  typeLine,
} from '../src/test-support/view-browser.js';

const TIMEOUT_MS = 30_000;

/** The lines of the last reply to `line` in the shell terminal's output (from its echo on). */
async function replyTo(runner, line) {
  const before = runner.stdoutText.length;
  return async (page) => {
    await typeLine(page, line);
    const until = Date.now() + TIMEOUT_MS;
    for (;;) {
      const text = runner.stdoutText.slice(before).replace(/\r/g, '');
      const at = text.indexOf(`${line}\n`);
      if (at >= 0) {
        const lines = text.slice(at).split('\n');
        const end = lines.findIndex((l) => /^(> )*(ok|error:)/.test(l));
        if (end > 0) {
          return lines.slice(1, end).map((l) => l.replace(/^(> )+/, ''));
        }
      }
      assert.ok(Date.now() < until, `no reply to ${line}: ${text}`);
      await new Promise((resolve) => setTimeout(resolve, 100));
    }
  };
}

/** `config`'s setting lines, typed on the page. */
async function config(runner, page) {
  const lines = await (await replyTo(runner, 'config'))(page);
  return lines.filter((l) => l.startsWith('# '));
}

/** Presses a panel key once the panel waits for one. */
async function press(page, stage, key) {
  await page.waitForSelector(`#calibrate[data-stage="${stage}"][data-busy="false"]`, {
    timeout: TIMEOUT_MS,
  });
  const selector =
    key === 'q'
      ? '#calibrate-quit'
      : `#calibrate-${stage === 'servo' ? 'keys' : 'next'} [data-key="${key}"]`;
  const taken = await page.evaluate(() =>
    Number(document.getElementById('calibrate').dataset.keys ?? 0),
  );
  await page.click(selector);
  await page.waitForFunction(
    (n) => Number(document.getElementById('calibrate').dataset.keys ?? 0) > n,
    taken,
    { timeout: TIMEOUT_MS },
  );
}

test('the page calibration: quit leaves the settings; the whole flow saves the trims', async (t) => {
  if (skipWithoutChromium(t, 'the page calibration')) {
    return;
  }
  const runner = startRunner();
  t.after(() => runner.kill('SIGKILL'));
  const url = await runner.url;
  const { page, pageErrors } = await openPage(t, { width: 1200, height: 1000 });
  await page.goto(url);
  await page.waitForSelector('#fk-status[data-status="solved"]', { timeout: TIMEOUT_MS });

  // The board's listings, for the expected trims.
  const listed = await (await replyTo(runner, 'geometry'))(page);
  const settingsBefore = await config(runner, page);
  const servos = servosFromListings([...listed, ...settingsBefore]);

  await t.test('quit after one servo: config as it was', async () => {
    await page.click('#calibrate-start');
    await press(page, 'servo', ']');
    await press(page, 'servo', 'Enter');
    await press(page, 'servo', '+');
    await press(page, 'servo', 'q');
    await page.waitForSelector('#calibrate[data-stage="stopped"]', { timeout: TIMEOUT_MS });
    assert.match(
      await page.textContent('#calibrate-text'),
      /Calibration stopped: pulses and trims as they were/,
    );
    assert.deepEqual(await config(runner, page), settingsBefore);
  });

  await t.test(
    'the whole flow: trims saved, listed by config, back after a power cycle',
    async () => {
      await page.click('#calibrate-start');
      const keys = [[']', ']', '+'], ['-'], [], ['[', '+'], [']'], ['-', '-']];
      const steps = [21, -1, 0, -9, 10, -2];
      for (const servoKeys of keys) {
        for (const key of servoKeys) {
          await press(page, 'servo', key);
        }
        await press(page, 'servo', 'Enter');
      }
      for (let i = 0; i < 5; i++) {
        await press(page, 'check', 'Enter');
      }
      await page.waitForSelector('#calibrate[data-stage="saved"]', { timeout: TIMEOUT_MS });
      // eq. 13 / 14 at alpha = 0: the flow starts at W0 - d r alpha0 (to 0.01 us); the trim of an
      // arm level at W is W + d r alpha0.
      const expected = servos.map((s, i) => expectedTrim(s, steps[i]));
      const trimsIn = (lines) =>
        [1, 2, 3, 4, 5, 6].map((n) =>
          Number(lines.find((l) => l.startsWith(`# servo${n}:`)).match(/trim_us=(\S+)/)[1]),
        );
      const after = await config(runner, page);
      trimsIn(after).forEach((t, i) =>
        assert.ok(Math.abs(t - expected[i]) <= 0.011, `${trimsIn(after)} ${expected}`),
      );
      assert.ok(
        after.some((l) => l.startsWith('# saved: yes')),
        after.join('\n'),
      );
      const shown = await page.textContent('#calibrate-result');
      assert.match(shown, /\[servo1\]\ntrim_us = \d+\.\d\d/);

      // Unsaved change, then a power cycle: the saved trims come back.
      await (
        await replyTo(runner, 'set servo2.trim_us 1555')
      )(page);
      runner.kill('SIGUSR2');
      await new Promise((resolve) => setTimeout(resolve, 1000));
      const again = await config(runner, page);
      assert.deepEqual(trimsIn(again), trimsIn(after));
      assert.ok(
        again.some((l) => l.startsWith('# saved: yes')),
        again.join('\n'),
      );
      assert.deepEqual(pageErrors, []);
    },
  );
});
