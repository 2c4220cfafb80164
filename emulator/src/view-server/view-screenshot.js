#!/usr/bin/env node
// Takes the README's picture of the live 3D view (`./dev screenshot [out.png]` runs it): starts
// `./dev run`, opens the page in headless Chromium (1280 x 800 px), types a pose from the golden
// table into the page's terminal line, waits for the readout to show it and saves a PNG of the
// whole page. (Chromium's own `--screenshot` cannot wait for the live event stream: with
// `--virtual-time-budget` it never returns, without it it shoots the page still connecting.)
// Usage: node emulator/src/view-server/view-screenshot.js [out.png]  (default emulator/view/screenshot.png)

import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import {
  CHROMIUM,
  haveChromium,
  launchChromium,
  startRunner,
  typeLine,
  waitForPose,
} from '../test-support/view-browser.js';

const out =
  process.argv[2] ??
  join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'view', 'screenshot.png');
/** "combined" in docs/geometry-and-calibration.md's golden table: x y z (mm), roll pitch yaw. */
const POSE = [4, -6, 5, 3, -4, 6];

if (!haveChromium()) {
  console.error(`no Chromium at ${CHROMIUM} (apt-get install chromium, or set CHROMIUM=path)`);
  process.exit(1);
}
const runner = startRunner();
let browser;
try {
  const url = await runner.url;
  browser = await launchChromium();
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  await page.goto(url);
  await page.waitForSelector('#fk-status[data-status="solved"]', { timeout: 30_000 });
  await typeLine(page, 'help');
  await typeLine(page, `pose ${POSE.join(' ')}`);
  await waitForPose(page, POSE, 0.05, 30_000);
  await page.waitForTimeout(500);
  await page.screenshot({ path: out });
  console.log(`wrote ${out}`);
} finally {
  await browser?.close();
  runner.kill('SIGINT');
  await runner.exited;
}
