// `hexapod view` (cli/src/view/) in a real browser, against the emulated board on its
// pseudo-terminal as against a board on a cable: `./dev run --pty --no-view` (the USB port on the
// pty, or UART0 with --uart), the tool serving the page for that port, the page opened in headless
// Chromium. Expected values come from the commands sent, never from the view's code:
// - after `pose 0 0 10 0 0 0` typed in the page's terminal the readout's forward-kinematics pose
//   is that pose within 0.05 mm / degree (computed from the pulses the board reports);
// - the page's terminal shows the typed line and its reply, never the tool's `pulses` queries nor
//   the listings it asked for;
// - the jog's arrow keys move the board: the pins the emulator measures reach the pulses of the
//   pose the page then shows, and the readout passed through poses in between (a move);
// - the page keeps being updated: the rate the tool measures (wall time) and the page shows is
//   reported, and must be at least 5 a second here. The emulated board answers only as fast as
//   the emulator runs, which on a loaded machine is well below real time, so the figures a board
//   gives (>= 30 a second over USB, >= 10 over UART0 at 115,200 baud) are checked in emulated
//   time, where the wire is modelled, by commands.test.js's `pulses` case.
// Skipped, saying so, where Chromium is missing.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import { COUNT_US, firmwareBootrom, pinsUs } from '../src/test-support/e2e-support.js';
import { buildTool, startPtyRunner, startToolView } from '../src/test-support/pty-runner.js';
import {
  jogRightSampled,
  openPage,
  skipWithoutChromium,
  typeLine,
  waitForPose,
} from '../src/test-support/view-browser.js';

const SETTLE_TIMEOUT_MS = 30_000;

/** The page's update rate as it shows it (`..., N updates/s`). */
async function rateShown(page) {
  const text = await page.textContent('#emulated-time');
  const found = /([\d.]+) updates\/s/.exec(text ?? '');
  return found ? Number(found[1]) : 0;
}

/** Updates a second the page must show at least, whatever the emulator's speed. */
const FOLLOWING_HZ = 5;

for (const { name, args } of [
  { name: 'USB', args: [] },
  { name: 'UART0', args: ['--uart'] },
]) {
  test(`hexapod view of a board on ${name}: the page follows a pose, the jog moves the board`, async (t) => {
    if (skipWithoutChromium(t, 'the browser test of hexapod view')) {
      return;
    }
    firmwareBootrom(); // the ELF built and the boot ROM cached before the runner needs them
    const tool = buildTool();
    const board = await startPtyRunner({ args: ['--no-view', ...args] });
    let view;
    t.after(() => {
      view?.child.kill('SIGINT');
      board.runner.kill();
    });
    view = await startToolView(tool, board.port);
    const { page, pageErrors } = await openPage(t, { width: 1200, height: 800 });
    await page.goto(view.url);
    await page.waitForSelector('#fk-status[data-status="solved"]', { timeout: SETTLE_TIMEOUT_MS });
    assert.match(await page.textContent('#title-source'), new RegExp(`board on ${board.port}`));

    // A pose typed in the page's terminal: the readout follows it.
    await typeLine(page, 'pose 0 0 10 0 0 0');
    await waitForPose(page, [0, 0, 10, 0, 0, 0], 0.05, SETTLE_TIMEOUT_MS);
    const terminal = () =>
      page.evaluate(
        () => /** @type {HTMLElement} */ (document.querySelector('#terminal')).innerText,
      );
    await page.waitForFunction(
      () =>
        /pose 0 0 10 0 0 0\s+ok/.test(
          /** @type {HTMLElement} */ (document.querySelector('#terminal')).innerText,
        ),
      null,
      { timeout: SETTLE_TIMEOUT_MS },
    );

    // The jog: five presses of the right arrow, x to 5 mm, sampled on the way.
    await page.locator('#stage').click();
    await page.waitForTimeout(1700); // the sliders follow the pose again
    const { seen, between } = await jogRightSampled(page, {
      expected: [5, 0, 10, 0, 0, 0],
      tolerance: 0.05,
      timeout: SETTLE_TIMEOUT_MS,
      everyMs: 30,
    });
    assert.ok(between.length >= 1, `x on the way to 5 mm: ${seen.join(', ')}`);
    // At the pins: what the emulator measures is what the page shows (one PWM count).
    await page.waitForTimeout(1500);
    const shown = await page.evaluate(() =>
      [1, 2, 3, 4, 5, 6].map((i) => Number(document.getElementById(`pulse-${i}`).textContent)),
    );
    const pins = pinsUs(board.log());
    shown.forEach((us, i) =>
      assert.ok(
        Math.abs(us - pins[i]) <= COUNT_US + 0.01,
        `servo ${i + 1}: page ${us}, pins ${pins[i]}`,
      ),
    );
    assert.ok(Math.abs(shown[0] - 1500) > 20, `the pins moved: ${shown}`);

    // Nothing of the tool's own traffic in the terminal.
    const text = await terminal();
    for (const word of ['pulses', 'pulse_us', '# layout', 'frame_hz', 'move x']) {
      assert.ok(!text.includes(word), `'${word}' in the page's terminal:\n${text}`);
    }

    const rate = await rateShown(page);
    t.diagnostic(`${name}: ${rate} updates a second (wall time)`);
    assert.ok(rate >= FOLLOWING_HZ, `${rate} updates a second on ${name}`);
    assert.deepEqual(pageErrors, []);
  });
}
