// The 3D view's web server (`./dev run` starts it; `--no-view` does not). It serves the page
// (emulator/view/), three.js and xterm.js from node_modules and the view's WebAssembly
// kinematics (view-kinematics, built into target/), and streams to the page what a logic
// analyser and a second serial host would see: the six pulse widths measured on the servo pins
// (ns, exact to the PWM count), the serial output of your terminal's link (bytes), and the
// board's own `geometry` and `config` listings. The page's typed lines come back as whole lines
// on your terminal's link through SharedInput. The listings, and the page's jog commands
// (POST /command, answered with the board's reply), go on the view's own link instead
// (view-link.js: UART0 while your terminal is on USB, USB with --uart), so they never show on
// your terminal. Nothing here computes kinematics: the page does, from the pins, with the
// project's own code.
//
// Server-Sent Events carry the stream (node's http is enough; no WebSocket library): at most
// one pin update per FRAME_MS (60 a second) and only when a width changed or a second passed,
// nothing at all while no page is connected, and a client that cannot keep up misses updates
// rather than slowing the emulator. Listens on 127.0.0.1 only.

import { createReadStream, existsSync, statSync } from 'node:fs';
import { createServer } from 'node:http';
import { dirname, extname, join, resolve, sep } from 'node:path';
import { fileURLToPath } from 'node:url';

import { ListingReader } from '../../view/board-listings.js';
import { listingsChangedBy } from './listing-changes.js';
import { ViewLink } from './view-link.js';

const EMULATOR = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const REPO = join(EMULATOR, '..');
/** The view's kinematics as `cargo build -p view-kinematics --release --target
 * wasm32-unknown-unknown` leaves it (`./dev run` builds it). */
export const VIEW_WASM = join(
  REPO,
  'target',
  'wasm32-unknown-unknown',
  'release',
  'view_kinematics.wasm',
);
/** The port `./dev run` tries first (RP2040); any free one if it is taken. */
export const DEFAULT_VIEW_PORT = 2040;

/** Shortest time between two pin updates to a page, ms (60 a second). */
export const FRAME_MS = 1000 / 60;
/** Pins are sent at least this often (the page shows emulated time moving), ms. */
const HEARTBEAT_MS = 1000;
/** Serial output kept for a page that connects later, bytes. */
const SCROLLBACK_BYTES = 16 * 1024;
/** Longest line the page may send, characters (the firmware refuses > 128 itself). */
const MAX_PAGE_LINE = 1024;

/** URL prefix -> directory, and the sub-folders of it that may be served. */
const STATIC = [
  { prefix: '/view/', dir: join(EMULATOR, 'view'), allow: [''] },
  {
    prefix: '/vendor/three/',
    dir: join(EMULATOR, 'node_modules', 'three'),
    allow: ['build', 'examples/jsm'],
  },
  {
    prefix: '/vendor/xterm/',
    dir: join(EMULATOR, 'node_modules', '@xterm', 'xterm'),
    allow: ['lib', 'css'],
  },
];

const CONTENT_TYPES = {
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.mjs': 'text/javascript; charset=utf-8',
  '.css': 'text/css; charset=utf-8',
  '.map': 'application/json',
  '.wasm': 'application/wasm',
  '.png': 'image/png',
  '.svg': 'image/svg+xml',
};

/**
 * Starts the server; resolves to a ViewServer once it listens. `port` 0 takes any free port;
 * another port that is taken falls back to any free one when `fallback` is set.
 * @param {object} options
 * @param {import('../chip/board.js').EmulatedBoard} options.board
 * @param {object} [options.serial] the serial link the page and the terminal share (one with
 *   `onOutput(listener)`: `board.usb`, `board.uart`; default the board, UART0)
 * @param {object} options.queries the view's own link, for the listings and the page's
 *   commands (`sendBytes`, `onOutput`: the other one of `board.uart`, `board.usb`)
 * @param {import('./shared-input.js').SharedInput} options.input
 * @param {string} [options.link] what the terminal side is, for the page ('terminal', 'pty')
 * @param {number} [options.port] the port to listen on (default `DEFAULT_VIEW_PORT`)
 * @param {boolean} [options.fallback] take any free port if `port` is taken (default true)
 * @param {string} [options.wasm] the view's WebAssembly module (default: the release build)
 */
export async function startViewServer({
  board,
  serial = board,
  queries,
  input,
  port = DEFAULT_VIEW_PORT,
  fallback = true,
  link = 'terminal',
  wasm = VIEW_WASM,
}) {
  const view = new ViewServer({ board, serial, queries, input, link, wasm });
  await view.listen(port, fallback);
  return view;
}

export class ViewServer {
  constructor({ board, serial = board, queries, input, link, wasm }) {
    this.board = board;
    this.input = input;
    this.link = link;
    this.wasm = wasm;
    /** Connected pages: `{ res, ready }` (ready: its socket took the last write). */
    this.clients = new Set();
    this.listings = { geometry: null, config: null };
    this.reader = new ListingReader();
    this.scrollback = [];
    this.pendingOutput = [];
    this.lastPins = null;
    this.lastPinsAt = 0;
    this.timer = null;
    this.stopped = null;

    serial.onOutput((byte) => this.output(byte));
    input.onLine((text) => this.ask(listingsChangedBy(text)));
    this.queries = new ViewLink(queries);
    this.queries.onLine((line) => this.listingLine(line));
    this.queries.onBanner(() => {
      // A (re)booted board, or the port opened: its settings may be its defaults again.
      this.queries.request('set echo off');
      this.ask(['geometry', 'config']);
    });
  }

  /** @returns {Promise<void>} */
  listen(port, fallback) {
    this.server = createServer((req, res) => this.handle(req, res));
    return new Promise((resolvePromise, reject) => {
      const onError = (error) => {
        if (error.code === 'EADDRINUSE' && fallback && port !== 0) {
          this.server.listen(0, '127.0.0.1');
        } else {
          reject(error);
        }
      };
      this.server.on('error', onError);
      this.server.once('listening', () => {
        this.server.off('error', onError);
        this.port = /** @type {import('node:net').AddressInfo} */ (this.server.address()).port;
        resolvePromise();
      });
      this.server.listen(port, '127.0.0.1');
    });
  }

  /** The page's address. */
  get url() {
    return `http://127.0.0.1:${this.port}/`;
  }

  // ---- what the board says ----

  output(byte) {
    this.scrollback.push(byte);
    if (this.scrollback.length > 2 * SCROLLBACK_BYTES) {
      this.scrollback = this.scrollback.slice(-SCROLLBACK_BYTES);
    }
    if (this.clients.size > 0) {
      this.pendingOutput.push(byte);
    }
  }

  /** A line on the view's own link: part of a listing, perhaps. */
  listingLine(line) {
    const listing = this.reader.line(line);
    if (listing) {
      this.listings[listing.kind] = listing[listing.kind];
      this.broadcast(listing.kind, listing[listing.kind]);
    }
  }

  /** Asks the board for `geometry` / `config` on the view's own link. */
  ask(listings) {
    if (listings.length === 0) {
      return;
    }
    this.broadcast('asking', { listings });
    for (const name of listings) {
      this.queries.request(name);
    }
  }

  // ---- the stream to the pages ----

  start() {
    this.timer ??= setInterval(() => this.tick(), FRAME_MS);
  }

  tick() {
    if (this.clients.size === 0) {
      clearInterval(this.timer);
      this.timer = null;
      this.pendingOutput = [];
      return;
    }
    if (this.pendingOutput.length > 0) {
      this.broadcast('uart', { text: Buffer.from(this.pendingOutput).toString('latin1') });
      this.pendingOutput = [];
    }
    const pins = this.pins();
    const now = performance.now();
    const key = JSON.stringify([pins.widthNs, pins.live]);
    if (key !== this.lastPins || now - this.lastPinsAt >= HEARTBEAT_MS) {
      this.lastPins = key;
      this.lastPinsAt = now;
      this.broadcast('pins', pins, { droppable: true });
    }
  }

  /** What the logic analyser on the servo pins measures now (ns). */
  pins() {
    const servos = this.board.servos();
    return {
      nanos: this.board.nanos,
      widthNs: servos.map((s) => s.widthNanos),
      periodNs: servos.map((s) => s.periodNanos),
      live: servos.map((s) => s.live),
    };
  }

  broadcast(event, data, { droppable = false } = {}) {
    const message = `event: ${event}\ndata: ${JSON.stringify(data)}\n\n`;
    for (const client of this.clients) {
      if (droppable && !client.ready) {
        continue; // the page is behind: it gets the next update instead
      }
      this.send(client, message);
    }
  }

  send(client, message) {
    client.ready = client.res.write(message);
    if (!client.ready) {
      client.res.once('drain', () => {
        client.ready = true;
      });
    }
  }

  events(req, res) {
    res.writeHead(200, {
      'Content-Type': 'text/event-stream',
      'Cache-Control': 'no-store',
      Connection: 'keep-alive',
    });
    const client = { res, ready: true };
    if (this.stopped !== null) {
      this.send(client, `event: stopped\ndata: ${JSON.stringify({ reason: this.stopped })}\n\n`);
      res.end();
      return;
    }
    const hello = { link: this.link, frameMs: FRAME_MS, source: 'emulator' };
    this.send(client, `event: hello\ndata: ${JSON.stringify(hello)}\n\n`);
    for (const kind of ['geometry', 'config']) {
      if (this.listings[kind]) {
        this.send(client, `event: ${kind}\ndata: ${JSON.stringify(this.listings[kind])}\n\n`);
      }
    }
    const history = Buffer.from(this.scrollback.slice(-SCROLLBACK_BYTES)).toString('latin1');
    this.send(client, `event: uart\ndata: ${JSON.stringify({ text: history })}\n\n`);
    this.send(client, `event: pins\ndata: ${JSON.stringify(this.pins())}\n\n`);
    this.clients.add(client);
    req.on('close', () => this.clients.delete(client));
    this.start();
  }

  // ---- HTTP ----

  handle(req, res) {
    // Only pages from this server: a foreign Host (DNS rebinding) or Origin is refused.
    const hosts = [`127.0.0.1:${this.port}`, `localhost:${this.port}`];
    if (!hosts.includes(req.headers.host)) {
      return this.fail(res, 403, 'forbidden host');
    }
    const url = new URL(req.url, `http://${req.headers.host}`);
    if (req.method === 'POST' && url.pathname === '/uart') {
      return this.typedLine(req, res, (line) => {
        const held = this.input.sendLine(line, 'page');
        res.writeHead(200, { 'Content-Type': 'application/json' });
        res.end(JSON.stringify({ held }));
      });
    }
    if (req.method === 'POST' && url.pathname === '/command') {
      return this.typedLine(req, res, async (line) => {
        const answer = await this.queries.request(line);
        this.ask(listingsChangedBy(line));
        res.writeHead(200, { 'Content-Type': 'application/json' });
        res.end(JSON.stringify(answer));
      });
    }
    if (req.method !== 'GET' && req.method !== 'HEAD') {
      return this.fail(res, 405, 'method not allowed');
    }
    if (url.pathname === '/events') {
      return this.events(req, res);
    }
    if (url.pathname === '/' || url.pathname === '/index.html') {
      return this.file(res, join(EMULATOR, 'view', 'index.html'));
    }
    if (url.pathname === '/view-kinematics.wasm') {
      if (!existsSync(this.wasm)) {
        return this.fail(res, 404, `${this.wasm} is not built: run ./dev run`);
      }
      return this.file(res, this.wasm);
    }
    for (const { prefix, dir, allow } of STATIC) {
      if (url.pathname.startsWith(prefix)) {
        const path = resolve(dir, `.${decodeURIComponent(url.pathname.slice(prefix.length - 1))}`);
        const allowed = allow.some((sub) => path.startsWith(join(dir, sub) + sep));
        if (allowed) {
          return this.file(res, path);
        }
      }
    }
    return this.fail(res, 404, 'not found');
  }

  file(res, path) {
    let stat;
    try {
      stat = statSync(path);
    } catch {
      return this.fail(res, 404, 'not found');
    }
    if (!stat.isFile()) {
      return this.fail(res, 404, 'not found');
    }
    res.writeHead(200, {
      'Content-Type': CONTENT_TYPES[extname(path)] ?? 'application/octet-stream',
      'Content-Length': stat.size,
      'Cache-Control': 'no-store',
    });
    createReadStream(path).pipe(res);
  }

  /**
   * POST /uart `{ "line": "pose 0 0 10 0 0 0" }`: one line typed on the page, for the shared
   * link (answer `{ held }`); POST /command `{ "line": "move x=5" }`: one of the page's own
   * commands, on the view's link (answer `{ reply, data }`: the board's final reply and data
   * lines). `then(line)` answers once the request is checked.
   */
  typedLine(req, res, then) {
    const origin = req.headers.origin;
    if (origin !== undefined && origin !== `http://${req.headers.host}`) {
      return this.fail(res, 403, 'forbidden origin');
    }
    // JSON only: a cross-site form or simple request cannot send it without asking first.
    if (!/^application\/json\b/.test(req.headers['content-type'] ?? '')) {
      return this.fail(res, 415, 'send JSON');
    }
    let body = '';
    req.setEncoding('latin1');
    req.on('data', (chunk) => {
      body += chunk;
      if (body.length > 4 * MAX_PAGE_LINE) {
        req.destroy();
      }
    });
    req.on('end', () => {
      let line;
      try {
        ({ line } = JSON.parse(body));
      } catch {
        return this.fail(res, 400, 'not JSON');
      }
      if (typeof line !== 'string' || line.length > MAX_PAGE_LINE || /[\r\n]/.test(line)) {
        return this.fail(res, 400, `one line of at most ${MAX_PAGE_LINE} characters`);
      }
      if (this.stopped !== null) {
        return this.fail(res, 503, this.stopped);
      }
      return then(line);
    });
  }

  fail(res, status, message) {
    res.writeHead(status, { 'Content-Type': 'text/plain; charset=utf-8' });
    res.end(`${message}\n`);
  }

  /**
   * Tells every page the emulator stopped (and why), then closes. Resolves when the pages have
   * been told (or after a short wait), so the process can exit.
   */
  async close(reason) {
    this.stopped = reason;
    clearInterval(this.timer);
    this.timer = null;
    const ended = [];
    for (const client of this.clients) {
      client.res.write(`event: stopped\ndata: ${JSON.stringify({ reason })}\n\n`);
      ended.push(new Promise((done) => client.res.end(done)));
    }
    this.clients.clear();
    this.server.close();
    const wait = new Promise((done) => setTimeout(done, 300).unref());
    await Promise.race([Promise.all(ended), wait]);
    this.server.closeAllConnections();
  }
}
