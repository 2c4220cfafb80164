// The page's terminal: xterm.js shows everything the board sends on its serial link (the same
// bytes the shell's terminal or pty gets: everyone on the link sees every reply), and an input
// line sends whole lines (POST /uart); the runner injects them as UART receive bytes, after any
// line half-typed in the shell's terminal (emulator/src/view-server/shared-input.js). Up/Down recall
// earlier lines.

import { Terminal } from '@xterm/xterm';

const FONT_SIZE = 13;

export class PageTerminal {
  constructor({ container, form, input, note }) {
    this.term = new Terminal({
      convertEol: true, // the board ends lines with LF only
      disableStdin: true, // typing happens in the input line, a whole line at a time
      fontSize: FONT_SIZE,
      scrollback: 2000,
      theme: { background: '#0d1014' },
    });
    this.term.open(container);
    this.container = container;
    this.input = input;
    this.note = note;
    this.history = [];
    this.recall = 0;
    new ResizeObserver(() => this.fit()).observe(container);
    this.fit();

    form.addEventListener('submit', (event) => {
      event.preventDefault();
      this.send(input.value);
    });
    input.addEventListener('keydown', (event) => this.key(event));
  }

  /** Columns and rows for the container's size (xterm's cells are about 0.6 x 1.2 em). */
  fit() {
    const cols = Math.max(20, Math.floor((this.container.clientWidth - 16) / (FONT_SIZE * 0.6)));
    const rows = Math.max(4, Math.floor((this.container.clientHeight - 8) / (FONT_SIZE * 1.2)));
    this.term.resize(cols, rows);
  }

  /** Bytes from the board (a latin1 string). */
  write(text) {
    this.term.write(text);
  }

  key(event) {
    if (event.key !== 'ArrowUp' && event.key !== 'ArrowDown') {
      return;
    }
    event.preventDefault();
    const step = event.key === 'ArrowUp' ? -1 : 1;
    this.recall = Math.min(Math.max(this.recall + step, 0), this.history.length);
    this.input.value = this.history[this.recall] ?? '';
  }

  async send(line) {
    if (this.history.at(-1) !== line && line.trim() !== '') {
      this.history.push(line);
    }
    this.recall = this.history.length;
    this.input.value = '';
    try {
      const response = await fetch('/uart', {
        method: 'POST',
        headers: { 'Content-Type': 'application/json' },
        body: JSON.stringify({ line }),
      });
      if (!response.ok) {
        throw new Error((await response.text()).trim());
      }
      const { held } = await response.json();
      this.note.textContent = held
        ? 'sent after the line half-typed in the shell terminal ends'
        : '';
    } catch (error) {
      this.note.textContent = `not sent: ${error.message}`;
    }
  }
}
