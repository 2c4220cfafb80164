// The view's plumbing without a browser: reading the board's listings out of its real output,
// two hosts sharing one UART (the shell terminal's keystrokes, the page's whole lines), and the
// view server's stream, typed lines, its own link's commands and refusals, against the real
// firmware in emulated time.
// Expected values come from docs/ (defaults, line editing), not from the code under test.

import assert from 'node:assert/strict';
import { request } from 'node:http';
import { before, test } from 'node:test';

import { ListingReader } from '../view/board-listings.js';
import { EmulatedBoard } from '../src/chip/board.js';
import { bootedBoard, firmwareBootrom } from '../src/test-support/e2e-support.js';
import { listingsChangedBy } from '../src/view-server/listing-changes.js';
import { SharedInput } from '../src/view-server/shared-input.js';
import { startViewServer } from '../src/view-server/view-server.js';

let bootrom;
before(() => {
  bootrom = firmwareBootrom();
});

/** Feeds every line of `lines` to a reader; returns the listings it finished. */
function read(lines, reader = new ListingReader()) {
  return lines.map((line) => reader.line(line)).filter(Boolean);
}

test("the board's geometry and config listings are read as docs/ documents them", () => {
  const board = bootedBoard(bootrom);
  const { lines } = board.request('geometry', { timeoutMs: 2000 });
  const [geometry] = read(lines);
  assert.equal(geometry.kind, 'geometry');
  const g = geometry.geometry;
  // docs/geometry-and-calibration.md: a = 20, s = 120, h0 = 118.458 mm, alpha0 = -0.252 degrees.
  assert.equal(g.armMm, 20);
  assert.equal(g.rodMm, 120);
  assert.equal(g.homeHeightMm, 118.458);
  assert.deepEqual(
    g.legs.map((leg) => leg.leg),
    [1, 2, 3, 4, 5, 6],
  );
  for (const leg of g.legs) {
    assert.equal(leg.alpha0Deg, -0.252);
    // Shafts on the 75 mm base circle, joints on the 60 mm platform circle.
    assert.ok(Math.abs(Math.hypot(...leg.baseMm) - 75) < 0.002, `${leg.baseMm}`);
    assert.ok(Math.abs(Math.hypot(...leg.platformMm) - 60) < 0.002, `${leg.platformMm}`);
  }

  const [config] = read(board.request('config', { timeoutMs: 2000 }).lines);
  assert.equal(config.kind, 'config');
  assert.equal(config.config.settings.frame_hz, '50');
  // docs/settings.md: trim 1500 us, 509.296 us/rad, even normal, odd reversed, 1100..1900,
  // not rated.
  config.config.servos.forEach((servo, i) => {
    assert.deepEqual(servo, {
      servo: i + 1,
      trimUs: 1500,
      rateUsRad: 509.296,
      dir: (i + 1) % 2 === 0 ? 'normal' : 'reversed',
      minUs: 1100,
      maxUs: 1900,
      torqueKgcm: null,
      speedS60deg: null,
    });
  });
  board.request('set servo2.torque_kgcm 2.5', { timeoutMs: 2000 });
  board.request('set servo5.speed_s_60deg 0.15', { timeoutMs: 2000 });
  const [rated] = read(board.request('config', { timeoutMs: 2000 }).lines);
  assert.deepEqual(
    rated.config.servos.map((servo) => servo.torqueKgcm),
    [null, 2.5, null, null, null, null],
  );
  assert.deepEqual(
    rated.config.servos.map((servo) => servo.speedS60deg),
    [null, null, null, null, 0.15, null],
  );

  // A changed setting shows in the next listing.
  board.request('set arm_mm 21', { timeoutMs: 2000 });
  const [changed] = read(board.request('geometry', { timeoutMs: 2000 }).lines);
  assert.equal(changed.geometry.armMm, 21);
});

test('a listing cut short or refused counts for nothing', () => {
  const board = bootedBoard(bootrom);
  const { lines } = board.request('geometry', { timeoutMs: 2000 });
  assert.deepEqual(read(lines.filter((line) => !/^# leg 3/.test(line))), [], 'a leg missing');
  assert.deepEqual(read([...lines.slice(0, -1), 'error:busy']), [], 'ended by an error');
  assert.deepEqual(read(lines.slice(0, -1)), [], 'no final reply yet');
});

test('which commands change which listing', () => {
  assert.deepEqual(listingsChangedBy('set rod_mm 130'), ['geometry']);
  assert.deepEqual(listingsChangedBy('SET base_half_angle_deg 15'), ['geometry']);
  assert.deepEqual(listingsChangedBy('set servo3.trim_us 1520'), ['config']);
  assert.deepEqual(listingsChangedBy('set servos.rate_us_rad 600'), ['config']);
  assert.deepEqual(listingsChangedBy('set pivot_z_mm 100'), ['config']);
  assert.deepEqual(listingsChangedBy('defaults'), ['geometry', 'config']);
  assert.deepEqual(listingsChangedBy('set speed_mm_s 10'), []);
  assert.deepEqual(listingsChangedBy('pose 0 0 5 0 0 0'), []);
});

/** A link that records what is sent on it. */
function recordingLink() {
  const sent = [];
  return {
    sent,
    text: () => Buffer.concat(sent).toString('latin1'),
    sendBytes: (b) => sent.push(Buffer.from(b)),
  };
}

test('a page line waits while the terminal has a half-typed line, then follows it whole', () => {
  const link = recordingLink();
  const input = new SharedInput(link);
  const lines = [];
  input.onLine((text, source) => lines.push(`${source}: ${text}`));

  input.typed(Buffer.from('pos'));
  assert.equal(input.sendLine('home', 'page'), true, 'held');
  assert.equal(link.text(), 'pos');
  input.typed(Buffer.from('e 0 0 1 0 0 0\r'));
  assert.equal(link.text(), 'pose 0 0 1 0 0 0\rhome\n');
  assert.deepEqual(lines, ['terminal: pose 0 0 1 0 0 0', 'page: home']);

  // With the terminal's line empty, a page line goes at once.
  assert.equal(input.sendLine('status', 'page'), false);
  assert.match(link.text(), /home\nstatus\n$/);
});

test("the terminal's line editing is followed as the firmware does it", () => {
  const link = recordingLink();
  const input = new SharedInput(link);
  const lines = [];
  input.onLine((text) => lines.push(text));
  // Backspace and DEL erase, Ctrl-U clears, arrows (ESC [ A) and ESC O P are ignored whole,
  // a lone ESC is ignored and what follows counts.
  input.typed(Buffer.from('sex\x7ft\x08t rod_mm 130\r'));
  input.typed(Buffer.from('junk\x15\x1b[Ahome\x1bOP\n'));
  input.typed(Buffer.from('\x1bstop\n'));
  assert.deepEqual(lines, ['set rod_mm 130', 'home', 'stop']);
  // Ctrl-C and Ctrl-X abandon the line: a held page line may go.
  input.typed(Buffer.from('pose 1'));
  input.sendLine('status', 'page');
  assert.equal(input.heldLines, 1);
  input.typed(Buffer.from([0x18]));
  assert.equal(input.heldLines, 0);
});

/**
 * An HTTP request to the view server: resolves to `{ status, body }`.
 * @param {number} port
 * @param {{ method?: string, path?: string, headers?: Record<string, string>, body?: string }}
 *   [options]
 */
function http(port, { method = 'GET', path = '/', headers = {}, body } = {}) {
  return new Promise((resolve, reject) => {
    const req = request({ host: '127.0.0.1', port, method, path, headers }, (res) => {
      let text = '';
      res.on('data', (chunk) => {
        text += chunk;
      });
      res.on('end', () => resolve({ status: res.statusCode, body: text }));
    });
    req.on('error', reject);
    req.end(body);
  });
}

/** Opens the event stream; `next(event)` resolves to the next message of that event's data. */
function events(port) {
  const queue = [];
  const waiting = [];
  let buffer = '';
  const req = request({ host: '127.0.0.1', port, path: '/events' }, (res) => {
    res.setEncoding('utf8');
    res.on('data', (chunk) => {
      buffer += chunk;
      let end;
      while ((end = buffer.indexOf('\n\n')) >= 0) {
        const block = buffer.slice(0, end);
        buffer = buffer.slice(end + 2);
        const event = /^event: (.*)$/m.exec(block)[1];
        const data = JSON.parse(/^data: (.*)$/m.exec(block)[1]);
        queue.push({ event, data });
        waiting.splice(0).forEach((wake) => wake());
      }
    });
  });
  req.end();
  return {
    /**
     * @param {string} event
     * @param {{ board?: EmulatedBoard }} [options]
     */
    async next(event, { board } = {}) {
      for (;;) {
        const index = queue.findIndex((m) => m.event === event);
        if (index >= 0) {
          return queue.splice(index, 1)[0].data;
        }
        board?.runMs(5); // let the emulated board answer while we wait
        await new Promise((wake) => {
          waiting.push(wake);
          setTimeout(wake, 20);
        });
      }
    },
    close: () => req.destroy(),
  };
}

/** Runs the emulated board until `promise` settles (an HTTP answer that needs the board). */
async function whileRunning(board, promise) {
  let settled = false;
  const result = promise.finally(() => {
    settled = true;
  });
  while (!settled) {
    board.runMs(5);
    await new Promise((wake) => setTimeout(wake, 5));
  }
  return result;
}

// (Each wait for an event loops until it comes: a listing the server never sends fails here,
// after a generous minute, instead of hanging the run.)
const STREAM_TEST = { timeout: 60_000 };

test(
  'the view server streams pins and listings, takes typed lines, and refuses strangers',
  STREAM_TEST,
  async (t) => {
    // As `./dev run` has it: the terminal on the USB port, the view's own questions on UART0.
    const board = new EmulatedBoard({ bootrom, usb: true });
    const input = new SharedInput(board.usb);
    const view = await startViewServer({
      board,
      serial: board.usb,
      queries: board.uart,
      input,
      port: 0,
    });
    t.after(() => view.close('test over'));
    board.boot(); // the banner on UART0: the view asks for the listings there
    board.runMs(200);
    const stream = events(view.port);
    t.after(() => stream.close());

    assert.equal((await stream.next('hello')).link, 'terminal');
    assert.equal((await stream.next('geometry', { board })).armMm, 20);
    assert.equal((await stream.next('config', { board })).servos.length, 6);
    // The output comes in batches at most 60 a second of wall time: a loaded machine may cut it
    // anywhere, so gather batches until the USB port's banner and prompt have come.
    let uart = '';
    while (!/hexapod control[^]*> /.test(uart)) {
      uart += (await stream.next('uart', { board })).text;
      assert.ok(uart.length < 100_000, `no banner in ${JSON.stringify(uart.slice(0, 300))}`);
    }
    const home = await stream.next('pins', { board });
    assert.deepEqual(home.live, [true, true, true, true, true, true]);

    // A typed line reaches the board like typing; a geometry setting makes the view ask again.
    const json = { 'Content-Type': 'application/json' };
    const sent = await http(view.port, {
      method: 'POST',
      path: '/uart',
      headers: json,
      body: '{"line":"set rod_mm 125"}',
    });
    assert.deepEqual([sent.status, JSON.parse(sent.body)], [200, { held: false }]);
    assert.deepEqual((await stream.next('asking', { board })).listings, ['geometry']);
    assert.equal((await stream.next('geometry', { board })).rodMm, 125);

    // Pins follow a move (heave up: odd servos' pulses shrink, the golden table of docs/geometry-and-calibration.md).
    await http(view.port, {
      method: 'POST',
      path: '/uart',
      headers: json,
      body: '{"line":"pose 0 0 5 0 0 0"}',
    });
    board.runMs(500);
    let pins;
    do {
      pins = await stream.next('pins', { board });
    } while (pins.widthNs[0] > 1450_000);
    assert.ok(pins.widthNs[1] > 1550_000, `${pins.widthNs}`);

    // The page's own commands go on the view's link and come back as the board's reply.
    const command = (line) =>
      whileRunning(
        board,
        http(view.port, {
          method: 'POST',
          path: '/command',
          headers: json,
          body: JSON.stringify({ line }),
        }),
      ).then(({ status, body }) => {
        assert.equal(status, 200, body);
        return JSON.parse(body);
      });
    assert.deepEqual(await command('move z=2'), { reply: 'ok', data: [] });
    const refusal = await command('pose 0 0 80 0 0 0');
    assert.match(refusal.reply, /^error:unreachable /);
    const pulses = await command('pulses');
    assert.equal(pulses.reply, 'ok');
    assert.match(pulses.data[0], /^# pulse_us: (\d+\.\d\d ?){6}$/);
    // A servo setting through it makes the view read `config` again.
    assert.deepEqual(await command('stop'), { reply: 'ok', data: [] });
    assert.equal((await command('set servo1.trim_us 1510')).reply, 'ok');
    let config;
    do {
      config = await stream.next('config', { board });
    } while (config.servos[0].trimUs !== 1510);

    // None of the view's questions, nor the page's commands, showed on the terminal's link.
    board.runMs(100);
    const terminal = Buffer.from(board.usb.outputBytes).toString('latin1');
    for (const word of ['geometry', '# layout:', 'config', 'move z=2', 'pulse_us', 'unreachable']) {
      assert.ok(!terminal.includes(word), `'${word}' on the terminal: ${JSON.stringify(terminal)}`);
    }
    assert.match(terminal, /set rod_mm 125\r?\nok/);

    // Strangers: another origin, a form post, a foreign Host (DNS rebinding), files outside.
    const origin = { ...json, Origin: 'http://evil.example' };
    assert.equal(
      (
        await http(view.port, {
          method: 'POST',
          path: '/uart',
          headers: origin,
          body: '{"line":"home"}',
        })
      ).status,
      403,
    );
    assert.equal(
      (
        await http(view.port, {
          method: 'POST',
          path: '/uart',
          headers: { 'Content-Type': 'text/plain' },
          body: 'home',
        })
      ).status,
      415,
    );
    assert.equal(
      (
        await http(view.port, {
          method: 'POST',
          path: '/uart',
          headers: json,
          body: '{"line":"a\\nb"}',
        })
      ).status,
      400,
    );
    assert.equal(
      (await http(view.port, { path: '/', headers: { Host: 'evil.example' } })).status,
      403,
    );
    assert.equal((await http(view.port, { path: '/view/..%2F..%2Fpackage.json' })).status, 404);
    assert.equal((await http(view.port, { path: '/vendor/three/package.json' })).status, 404);
    assert.equal((await http(view.port, { path: '/view/main.js' })).status, 200);
    assert.equal(
      (await http(view.port, { path: '/vendor/three/build/three.module.js' })).status,
      200,
    );

    // Stopping tells the page why.
    const stopped = stream.next('stopped');
    await view.close('the emulator stopped for a test');
    assert.equal((await stopped).reason, 'the emulator stopped for a test');
  },
);
