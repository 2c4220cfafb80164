// Two hosts typing on one serial link, as honestly as one wire allows: the terminal (or the
// program on the pseudo-terminal) sends its bytes as typed, keystroke by keystroke, because the
// firmware's echo and line editing need them; the 3D view's page, and the view itself when it
// asks for a listing, send whole lines. A whole line waits while the terminal has a line
// half-typed (the firmware would otherwise join the two into one), and goes out, in order, as
// soon as the terminal ends or abandons its line. Every byte still reaches the board as UART
// receive bytes at the board's baud rate, through the link's own `sendBytes`.
//
// The link is anything with `sendBytes(bytes)` and `onOutput(listener)` (the EmulatedBoard).

const LF = 0x0a;
const CR = 0x0d;
const BACKSPACE = 0x08;
const DELETE = 0x7f;
const CTRL_C = 0x03;
const CTRL_U = 0x15;
const CTRL_X = 0x18;
const ESC = 0x1b;

export class SharedInput {
  constructor(link) {
    this.link = link;
    /** What the terminal has typed since its last line end, after its line editing. */
    this.terminalLine = '';
    /** 'text' | 'esc' | 'csi' | 'ss3': where in an escape sequence the terminal is. */
    this.escape = 'text';
    /** Whole lines waiting for the terminal to finish its line: `{ text, source }`. */
    this.held = [];
    /** Called with `(text, source)` for every line sent, once it has gone to the link. */
    this.lineListeners = new Set();
  }

  /** Calls `listener(text, source)` for each complete line sent; returns an unsubscribe. */
  onLine(listener) {
    this.lineListeners.add(listener);
    return () => this.lineListeners.delete(listener);
  }

  /** True while the terminal has typed part of a line. */
  get terminalLineOpen() {
    return this.terminalLine.length > 0;
  }

  /** Lines waiting for the terminal's line to end. */
  get heldLines() {
    return this.held.length;
  }

  /**
   * The terminal's (or pty's) bytes, passed on at once. Tracks its line as the firmware edits
   * it (docs/commands.md, the protocol): printable characters add, backspace erases, Ctrl-U
   * clears, Ctrl-C / Ctrl-X abandon, CR or LF end it; escape sequences are skipped whole.
   */
  typed(bytes) {
    this.link.sendBytes(bytes);
    for (const byte of bytes) {
      this.track(byte);
    }
    if (!this.terminalLineOpen) {
      this.flush();
    }
  }

  track(byte) {
    if (byte === CR || byte === LF) {
      // A line end always ends the line, even inside an escape sequence.
      this.escape = 'text';
      if (this.terminalLine.length > 0) {
        const text = this.terminalLine;
        this.terminalLine = '';
        this.announce(text, 'terminal');
      }
      return;
    }
    if (this.escape === 'esc') {
      if (byte === 0x5b) {
        this.escape = 'csi';
      } else if (byte === 0x4f) {
        this.escape = 'ss3';
      } else if (byte !== ESC) {
        this.escape = 'text';
        this.track(byte); // a lone ESC is ignored: what follows counts
      }
      return;
    }
    if (this.escape === 'csi') {
      if (byte >= 0x40 && byte <= 0x7e) {
        this.escape = 'text'; // the final byte
      }
      return;
    }
    if (this.escape === 'ss3') {
      this.escape = 'text';
      return;
    }
    if (byte === ESC) {
      this.escape = 'esc';
    } else if (byte === BACKSPACE || byte === DELETE) {
      this.terminalLine = this.terminalLine.slice(0, -1);
    } else if (byte === CTRL_U || byte === CTRL_C || byte === CTRL_X) {
      this.terminalLine = '';
    } else if (byte >= 0x20) {
      this.terminalLine += String.fromCharCode(byte);
    }
  }

  /**
   * A whole line from `source` (e.g. 'page', 'view'); `text` must not contain a line end (one
   * LF is added). Sent now, or after the terminal's half-typed line ends. Returns whether it
   * had to wait.
   */
  sendLine(text, source) {
    if (/[\r\n]/.test(text)) {
      throw new Error('sendLine takes one line without its line end');
    }
    this.held.push({ text, source });
    if (this.terminalLineOpen) {
      return true;
    }
    this.flush();
    return false;
  }

  flush() {
    const lines = this.held;
    this.held = [];
    for (const { text, source } of lines) {
      this.link.sendBytes(Buffer.from(`${text}\n`, 'latin1'));
      this.announce(text, source);
    }
  }

  announce(text, source) {
    for (const listener of this.lineListeners) {
      listener(text, source);
    }
  }
}
