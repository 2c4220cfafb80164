// The live 3D view in a real browser: `./dev run` started as a user starts it, its page opened
// in headless Chromium (Debian's `chromium` package, driven by playwright-core; nothing
// downloads a browser of its own) and commands typed into the page's own terminal line.
// Expected values come from the commands typed, never from the view's code:
// - after `pose 0 0 10 0 0 0` the readout's forward-kinematics pose is that pose within
//   0.05 mm / 0.05 degree (it is computed from the measured pins only);
// - after a roll the platform in a screenshot is visibly tilted (the plate's top is drawn in one
//   known colour, #f28c28: its top edge is compared at the left and right of the picture);
// - the jog panel (keys, a slider, home) moves the board: the readout, computed from the pins,
//   passes through in-between poses (a move, not a jump) and arrives at what was asked;
// - the view's own questions (`geometry`, `config`) and the jog's commands never show on the
//   user's terminal (`./dev run`'s stdout: the USB port), only the lines typed on the page;
// - when the emulator stops, the page says so and keeps working (no script error).
// Where Chromium is missing the test is skipped with a message saying so (`./dev test` installs
// it with apt-get); CHROMIUM=path picks another binary.

import assert from 'node:assert/strict';
import { test } from 'node:test';

import {
  jogRightSampled,
  openPage,
  readPose,
  skipWithoutChromium,
  startRunner,
  typeLine,
  waitForPose,
} from '../src/test-support/view-browser.js';

/** The plate's top colour (emulator/view/scene.js, PLATFORM_COLOUR). */
const PLATE_RGB = [0xf2, 0x8c, 0x28];
/**
 * The jog's poses, read from the pins: 1,500 us is 4,687.5 PWM counts of 0.32 us, so the pins
 * carry the home pulses to half a count, and the forward kinematics of them is off by up to
 * ~0.12 mm or degree (yaw 0.104 degree at home). The jog's checks are of moves of millimetres.
 */
const JOG_TOLERANCE = 0.2;
/** Generous time-outs for what takes well under a second in real time, ms. */
const SETTLE_TIMEOUT_MS = 30_000;

/**
 * Where the plate's top edge is in a screenshot of the 3D stage: per column, the first row of
 * plate colour; the medians over the leftmost and rightmost 15% of the plate's columns (px,
 * rows count down). Decoded in a blank page of its own, not in the page under test.
 */
async function plateEdges(page, decoder) {
  const png = await page.locator('#stage canvas').screenshot();
  return decoder.evaluate(
    async ({ base64, rgb }) => {
      const image = new Image();
      image.src = `data:image/png;base64,${base64}`;
      await image.decode();
      const canvas = document.createElement('canvas');
      canvas.width = image.width;
      canvas.height = image.height;
      const context = canvas.getContext('2d');
      context.drawImage(image, 0, 0);
      const { data, width, height } = context.getImageData(0, 0, image.width, image.height);
      const top = [];
      for (let x = 0; x < width; x++) {
        for (let y = 0; y < height; y++) {
          const p = 4 * (y * width + x);
          if ([0, 1, 2].every((c) => Math.abs(data[p + c] - rgb[c]) <= 24)) {
            top.push([x, y]);
            break;
          }
        }
      }
      if (top.length === 0) {
        return null;
      }
      const [first, last] = [top[0][0], top.at(-1)[0]];
      const band = 0.15 * (last - first);
      const median = (rows) => rows.sort((a, b) => a - b)[Math.floor(rows.length / 2)];
      return {
        columns: top.length,
        left: median(top.filter(([x]) => x <= first + band).map(([, y]) => y)),
        right: median(top.filter(([x]) => x >= last - band).map(([, y]) => y)),
      };
    },
    { base64: png.toString('base64'), rgb: PLATE_RGB },
  );
}

test('the 3D view shows the pose the pins carry, tilts with a roll, and says when the emulator stops', async (t) => {
  if (skipWithoutChromium(t, 'the browser test of the 3D view')) {
    return;
  }
  const runner = startRunner();
  t.after(() => runner.kill('SIGKILL'));
  const url = await runner.url;
  const { browser, page, pageErrors } = await openPage(t, { width: 1200, height: 800 });
  const decoder = await browser.newPage();

  // The side camera looks along -x from +x: the base y axis points right on the screen.
  await page.goto(`${url}?camera=side`);
  await page.waitForSelector('#fk-status[data-status="solved"]', { timeout: SETTLE_TIMEOUT_MS });
  const level = await plateEdges(page, decoder);
  assert.ok(level && level.columns > 100, `the plate is on screen: ${JSON.stringify(level)}`);
  assert.ok(Math.abs(level.left - level.right) <= 2, `level plate: ${JSON.stringify(level)}`);

  await t.test(
    'pose 0 0 10 0 0 0: the readout shows it within 0.05 mm and 0.05 degree',
    async () => {
      await typeLine(page, 'pose 0 0 10 0 0 0');
      await waitForPose(page, [0, 0, 10, 0, 0, 0], 0.05, SETTLE_TIMEOUT_MS);
      // Still there once the move has ended (the platform holds the pose).
      await page.waitForTimeout(500);
      const pose = await readPose(page);
      [0, 0, 10, 0, 0, 0].forEach((v, i) =>
        assert.ok(Math.abs(pose[i] - v) <= 0.05, `pose ${pose}`),
      );
      // The page's line went over the one UART: the shell's terminal saw its echo and reply too.
      await page.waitForFunction(
        () =>
          /pose 0 0 10 0 0 0\s+ok/.test(
            /** @type {HTMLElement} */ (document.querySelector('#terminal')).innerText,
          ),
        null,
        { timeout: SETTLE_TIMEOUT_MS },
      );
      assert.match(runner.stdoutText, /pose 0 0 10 0 0 0\r?\nok/);
      // The view asked for the listings on UART0: the user's terminal saw none of it.
      assert.doesNotMatch(runner.stdoutText, /geometry|# layout:|# frame_hz:/);
    },
  );

  await t.test('a roll tilts the platform in the picture, +y side up', async () => {
    await typeLine(page, 'pose 0 0 0 8 0 0');
    await waitForPose(page, [0, 0, 0, 8, 0, 0], 0.05, SETTLE_TIMEOUT_MS);
    await page.waitForTimeout(300);
    const rolled = await plateEdges(page, decoder);
    assert.ok(rolled && rolled.columns > 100, JSON.stringify(rolled));
    // Rows count downwards: the right (+y) edge is higher, i.e. at a smaller row.
    assert.ok(
      rolled.left - rolled.right >= 10,
      `rolled plate: ${JSON.stringify({ level, rolled })}`,
    );
    t.diagnostic(
      `plate top edge left/right, px: level ${level.left}/${level.right}, rolled ${rolled.left}/${rolled.right}`,
    );
  });

  await t.test('the jog panel moves the board smoothly, and goes home', async () => {
    // Slow moves (5 mm take 0.5 s), so the readout, sampled every 40 ms of wall-clock time
    // whatever the machine's load, is seen on the way; the default speed is set back below.
    await typeLine(page, 'set speed_mm_s 10');
    await page.waitForTimeout(300);
    // h: home (from the roll above), through the board's own move.
    await page.locator('#stage').click(); // the focus off the typing line: keys jog
    await page.keyboard.press('h');
    await waitForPose(page, [0, 0, 0, 0, 0, 0], JOG_TOLERANCE, SETTLE_TIMEOUT_MS);
    await page.waitForTimeout(1700); // the sliders follow the pose again
    // Five presses of the right arrow: x = 5 mm, sampled on the way (a move, never a jump).
    const { seen, between } = await jogRightSampled(page, {
      expected: [5, 0, 0, 0, 0, 0],
      tolerance: JOG_TOLERANCE,
      timeout: SETTLE_TIMEOUT_MS,
      everyMs: 40,
    });
    assert.ok(between.length >= 2, `x on the way to 5 mm: ${seen.join(', ')}`);
    // A slider: z to 4 mm.
    await page.locator('#jog-z').fill('4');
    await waitForPose(page, [5, 0, 4, 0, 0, 0], JOG_TOLERANCE, SETTLE_TIMEOUT_MS);
    // The sliders' ranges are the board's own reach from home (`limits`: z 14.287 mm down).
    assert.equal(await page.getAttribute('#jog-z', 'min'), '-14');
    // Out of reach from here (servo 3 past its limit): refused in the board's words, the
    // slider goes back.
    await page.locator('#jog-roll').fill('13');
    await page.waitForSelector('#jog-note[data-reply="error:servo-limit"]', {
      timeout: SETTLE_TIMEOUT_MS,
    });
    assert.match(await page.textContent('#jog-note'), /servo 3 would need/);
    assert.equal(await page.inputValue('#jog-roll'), '0');
    // The home button.
    await page.click('#jog-home');
    await waitForPose(page, [0, 0, 0, 0, 0, 0], JOG_TOLERANCE, SETTLE_TIMEOUT_MS);
    await typeLine(page, 'set speed_mm_s 50');
    await page.waitForTimeout(300);
    // None of it showed on the user's terminal.
    assert.doesNotMatch(runner.stdoutText, /move |home|unreachable/);
  });
  await t.test(
    'with a pivot set, the readout is the pose about it (config carries it)',
    async () => {
      // 5 degrees of pitch about a point 100 mm up: about the platform's centre these pins would
      // read x = -8.7 mm, z = 0.4 mm (docs/settings.md, "The pivot").
      await typeLine(page, 'set pivot_z_mm 100');
      await typeLine(page, 'pose 0 0 0 0 5 0');
      await waitForPose(page, [0, 0, 0, 0, 5, 0], 0.05, SETTLE_TIMEOUT_MS);
      await page.waitForTimeout(300);
      const pose = await readPose(page);
      [0, 0, 0, 0, 5, 0].forEach((v, i) =>
        assert.ok(Math.abs(pose[i] - v) <= 0.05, `pose ${pose}`),
      );
    },
  );

  await t.test('when the emulator stops the page shows it, without a script error', async () => {
    const before = await readPose(page);
    runner.kill('SIGINT'); // as Ctrl-C would
    const { code } = await runner.exited;
    assert.equal(code, 0, runner.stderrText);
    await page.waitForFunction(
      () =>
        /stopped/.test(document.getElementById('link-state').textContent) &&
        !document.getElementById('overlay').hidden,
      null,
      { timeout: SETTLE_TIMEOUT_MS },
    );
    assert.match(await page.textContent('#overlay'), /emulator stopped/);
    // The last picture and readout stay.
    assert.deepEqual(await readPose(page), before);
    assert.equal(await page.locator('#stage canvas').count(), 1);
    assert.deepEqual(pageErrors, []);
  });
});
