// The view's own serial link (`./dev run`: UART0 while your terminal is on the USB port, the USB
// port with --uart), so that what the view asks the board (`geometry`, `config`, the page's jog
// commands) never shows on your terminal. A program's link as docs/commands.md describes one:
// echo off, one line at a time, each answered by its final reply (`ok` or `error:...`), the
// data lines before it; replies come back in order, so the oldest line waiting is the one a
// final reply answers. Notices (`# warning: ...`) and the banner are passed on as lines.
//
// The link is anything with `sendBytes(bytes)` and `onOutput(listener)` (board.uart, board.usb).

import { BANNER, FINAL_REPLY } from '../chip/board.js';

/** How long a line may wait for its reply before it counts as unanswered, ms (wall time). */
const REPLY_TIMEOUT_MS = 20_000;

export class ViewLink {
  constructor(link) {
    this.link = link;
    this.partial = '';
    /** Lines sent and not answered yet: `{ text, data, done }`, oldest first. */
    this.waiting = [];
    /** Called with every whole line the board sends on this link. */
    this.lineListeners = new Set();
    /** Called when the board greets this link (it powered up, or the port opened). */
    this.bannerListeners = new Set();
    link.onOutput((byte) => this.byte(byte));
  }

  onLine(listener) {
    this.lineListeners.add(listener);
  }

  onBanner(listener) {
    this.bannerListeners.add(listener);
  }

  /** Sends one line; resolves to `{ reply, data }` (its final reply and its data lines). */
  request(text) {
    return new Promise((resolve) => {
      const entry = { text, data: [], done: resolve };
      entry.timer = setTimeout(() => {
        this.waiting = this.waiting.filter((e) => e !== entry);
        resolve({ reply: 'error:no-reply the board did not answer', data: entry.data });
      }, REPLY_TIMEOUT_MS);
      entry.timer.unref?.();
      this.waiting.push(entry);
      this.link.sendBytes(Buffer.from(`${text}\n`, 'latin1'));
    });
  }

  byte(byte) {
    if (byte !== 0x0a && byte !== 0x0d) {
      this.partial += String.fromCharCode(byte);
      return;
    }
    // The prompt (`> `) comes before the next line while echo is still on: not part of it.
    const line = this.partial.replace(/^(> )+/, '');
    this.partial = '';
    if (line === '') {
      return;
    }
    if (BANNER.test(line)) {
      // A (re)booted board or a reopened port: echo is on again and nothing is in flight.
      for (const entry of this.waiting.splice(0)) {
        clearTimeout(entry.timer);
        entry.done({ reply: 'error:reset the board restarted', data: entry.data });
      }
      for (const listener of this.bannerListeners) {
        listener(line);
      }
    }
    for (const listener of this.lineListeners) {
      listener(line);
    }
    const entry = this.waiting[0];
    if (!entry) {
      return;
    }
    if (FINAL_REPLY.test(line)) {
      this.waiting.shift();
      clearTimeout(entry.timer);
      entry.done({ reply: line, data: entry.data });
    } else if (line.startsWith('# ') && line !== `> ${entry.text}`) {
      entry.data.push(line);
    }
  }
}
