// Drives the live 3D view from outside, as a user would: starts `./dev run` (UART0 on a pipe,
// the view on a free port) and opens its page in headless Chromium (Debian's `chromium`
// package, through playwright-core, which downloads no browser of its own). Used by
// test/view.test.js and src/view-server/view-screenshot.js.

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
