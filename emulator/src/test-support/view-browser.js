// Drives the live 3D view from outside, as a user would: starts `./dev run` (UART0 on a pipe,
// the view on a free port) and opens its page in headless Chromium (Debian's `chromium`
// package, through playwright-core, which downloads no browser of its own). Used by the
// browser tests (test/view*.test.js) and src/view-server/view-screenshot.js.

import { spawn } from 'node:child_process';
import { existsSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
/** The browser: Debian's chromium, or CHROMIUM=path. */
export const CHROMIUM = process.env.CHROMIUM ?? '/usr/bin/chromium';
/** `./dev run` may have to build the firmware and the view's WebAssembly first, ms. */
const START_TIMEOUT_MS = 600_000;

/** Whether the browser is there. */
export function haveChromium() {
  return existsSync(CHROMIUM);
}

/**
 * Starts `./dev run --view-port 0 [args]`. Returns the child process with `url` (a promise of
 * the view's address, from what it prints), `exited` (a promise of `{ code, signal }`),
 * `stdoutText` (UART0 as the shell terminal shows it) and `stderrText`.
 */
/**
 * @typedef {import('node:child_process').ChildProcessWithoutNullStreams & {
 *   url: Promise<string>, exited: Promise<{ code: number | null, signal: string | null }>,
 *   stdoutText: string, stderrText: string }} Runner
 */
/** @returns {Runner} */
export function startRunner(args = []) {
  const runner = /** @type {Runner} */ (
    spawn(join(REPO, 'dev'), ['run', '--view-port', '0', ...args], {
      cwd: REPO,
      stdio: ['pipe', 'pipe', 'pipe'],
    })
  );
  runner.stdoutText = '';
  runner.stderrText = '';
  runner.stdout.on('data', (data) => {
    runner.stdoutText += data.toString('latin1');
  });
  runner.exited = new Promise((resolve) => {
    runner.on('exit', (code, signal) => resolve({ code, signal }));
  });
  runner.url = new Promise((resolve, reject) => {
    const timer = setTimeout(
      () => reject(new Error(`no view address in:\n${runner.stderrText}`)),
      START_TIMEOUT_MS,
    );
    runner.stderr.on('data', (data) => {
      runner.stderrText += data.toString();
      const match = /3D view: (http:\/\/\S+)/.exec(runner.stderrText);
      if (match) {
        clearTimeout(timer);
        resolve(match[1]);
      }
    });
    runner.exited.then(({ code }) => {
      clearTimeout(timer);
      reject(new Error(`./dev run exited (${code}):\n${runner.stderrText}`));
    });
  });
  return runner;
}

/** Headless Chromium with software WebGL (no GPU needed). */
export async function launchChromium() {
  const { chromium } = await import('playwright-core');
  return chromium.launch({
    executablePath: CHROMIUM,
    args: [
      '--no-sandbox',
      '--disable-gpu',
      '--disable-background-networking',
      '--use-angle=swiftshader',
      '--enable-unsafe-swiftshader',
    ],
  });
}

/**
 * For a browser test: when Chromium is missing, skips `t`, saying on stderr that `what` did not
 * run and how to get it, and returns true (the test returns); otherwise false.
 */
export function skipWithoutChromium(t, what) {
  if (haveChromium()) {
    return false;
  }
  const why =
    `SKIPPED: no Chromium at ${CHROMIUM}, so ${what} did not run ` +
    `(./dev test installs Debian's chromium package with apt-get; CHROMIUM=path picks another)`;
  console.error(why);
  t.skip(why);
  return true;
}

/**
 * Headless Chromium, closed when test `t` ends, and a page of `viewport` ({ width, height })
 * whose script errors collect in `pageErrors`: `{ browser, page, pageErrors }`.
 */
export async function openPage(t, viewport) {
  const browser = await launchChromium();
  t.after(() => browser.close());
  const page = await browser.newPage({ viewport });
  /** @type {string[]} */
  const pageErrors = [];
  page.on('pageerror', (error) => pageErrors.push(error.message));
  return { browser, page, pageErrors };
}

/** Types a line into the page's terminal input and presses Enter. */
export async function typeLine(page, line) {
  await page.fill('#line', line);
  await page.press('#line', 'Enter');
}

/** The pose the page's readout shows: x, y, z (mm), roll, pitch, yaw (deg). */
export async function readPose(page) {
  return page.evaluate(() =>
    ['x', 'y', 'z', 'roll', 'pitch', 'yaw'].map((axis) =>
      Number(document.getElementById(`pose-${axis}`).textContent),
    ),
  );
}

/**
 * From x = 0, jogs x to 5 mm by five presses of the right arrow (the page's focus must be off
 * the typing line), sampling the readout's x every `everyMs` of wall-clock time until it shows
 * `expected` within `tolerance`. Returns the x values seen (`seen`, to 0.1 mm) and those
 * strictly between 0.2 and 4.8 mm (`between`: a move shows some on the way, a jump none).
 */
export async function jogRightSampled(page, { expected, tolerance, timeout, everyMs }) {
  const seen = new Set();
  const sampler = setInterval(async () => {
    const pose = await readPose(page).catch(() => null);
    if (pose) {
      seen.add(pose[0].toFixed(1));
    }
  }, everyMs);
  try {
    for (let i = 0; i < 5; i++) {
      await page.keyboard.press('ArrowRight');
    }
    await waitForPose(page, expected, tolerance, timeout);
  } finally {
    clearInterval(sampler);
  }
  return { seen: [...seen], between: [...seen].map(Number).filter((x) => x > 0.2 && x < 4.8) };
}

/** Waits until the readout shows `expected` within `tolerance` (mm and deg). */
export async function waitForPose(page, expected, tolerance, timeout) {
  await page.waitForFunction(
    ({ expected, tolerance }) => {
      const shown = ['x', 'y', 'z', 'roll', 'pitch', 'yaw'].map((axis) =>
        Number(document.getElementById(`pose-${axis}`).textContent),
      );
      return shown.every((v, i) => Math.abs(v - expected[i]) <= tolerance);
    },
    { expected, tolerance },
    { timeout, polling: 100 },
  );
}
