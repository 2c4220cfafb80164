// The host tool `hexapod` against the emulated board as a user runs them: `./dev run --pty
// --no-view` (src/run.js) boots the firmware ELF with UART0 on a pseudo-terminal, and the tool,
// built by cargo, talks to that terminal as to a board's serial port. Written once for the
// tests that do that (cli.test.js, cue.test.js, calibrate.test.js, view-board.test.js) and the
// cue latency benchmark.

import { execFileSync, spawn } from 'node:child_process';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { DEFAULT_ELF } from '../chip/board.js';

export const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
const RUNNER = join(REPO, 'emulator', 'src', 'run.js');

/** Builds the tool (debug, as `cargo build -p hexapod`); returns the path cargo reports. */
export function buildTool() {
  const output = execFileSync(
    'cargo',
    ['build', '--quiet', '-p', 'hexapod', '--message-format=json'],
    {
      cwd: REPO,
      encoding: 'utf8',
      maxBuffer: 64 * 1024 * 1024,
      stdio: ['ignore', 'pipe', 'inherit'],
    },
  );
  for (const line of output.split('\n')) {
    if (line.startsWith('{')) {
      const message = JSON.parse(line);
      const artifact = message.reason === 'compiler-artifact';
      if (artifact && message.target?.name === 'hexapod' && message.executable) {
        return message.executable;
      }
    }
  }
  throw new Error('cargo build did not report the hexapod executable');
}

/**
 * Starts the runner with UART0 on a pseudo-terminal (the ELF and the boot ROM must be ready:
 * `firmwareBootrom()` first), with `args` (no view unless told; e.g. `['--no-view', '--uart']`).
 * Resolves, once the runner has said where the terminal is, to `{ runner, port, log }`: the
 * child process, the terminal's path and a function returning everything the runner wrote to
 * stderr so far (with the `servos us: ...` lines of the pins it measures). `onText` sees that
 * text as it comes.
 * @param {{ args?: string[], onText?: (text: string) => void }} [options]
 */
export async function startPtyRunner({ args = ['--no-view'], onText = () => {} } = {}) {
  const runner = spawn(process.execPath, [RUNNER, '--pty', ...args, '--elf', DEFAULT_ELF], {
    stdio: ['ignore', 'ignore', 'pipe'],
  });
  let log = '';
  runner.stderr.setEncoding('utf8');
  runner.stderr.on('data', (text) => {
    log += text;
    onText(text);
  });
  const port = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`no pty after 60 s: ${log}`)), 60_000);
    const look = () => {
      const found = log.match(/is on (\/\S+)/);
      if (found) {
        clearTimeout(timer);
        runner.stderr.off('data', look);
        resolve(found[1]);
      }
    };
    runner.stderr.on('data', look);
    runner.on('exit', (code) => reject(new Error(`the runner exited (${code}): ${log}`)));
  });
  return { runner, port, log: () => log };
}

/**
 * Runs a program (asynchronously, so the runner keeps emulating); resolves to
 * `{ status, stdout, stderr }`. `input`, if given, is its whole standard input (then closed).
 * `onLine` sees each stdout or stderr line as it comes, with the wall-clock time it came.
 * @param {string} program
 * @param {string[]} args
 * @param {{ cwd?: string, input?: string, onLine?: (line: string, at: number) => void }} [options]
 */
export function runProgram(program, args, { cwd, input, onLine = () => {} } = {}) {
  return new Promise((resolve) => {
    const child = spawn(program, args, { cwd });
    let stdout = '';
    let stderr = '';
    const take = (chunk) => {
      for (const line of String(chunk).split('\n')) {
        if (line) {
          onLine(line, Date.now());
        }
      }
    };
    child.stdout.on('data', (d) => {
      stdout += d;
      take(d);
    });
    child.stderr.on('data', (d) => {
      stderr += d;
      take(d);
    });
    if (input !== undefined) {
      child.stdin.on('error', () => {}); // a program that exits before reading it all
      child.stdin.end(input);
    }
    child.on('close', (status) => resolve({ status, stdout, stderr }));
  });
}

/**
 * Starts `hexapod view --port PORT --view-port 0`; resolves to `{ child, url, stderr() }` once
 * it prints the page's address.
 * @param {string} tool
 * @param {string} port
 * @param {string[]} [args]
 */
export async function startToolView(tool, port, args = []) {
  const child = spawn(
    tool,
    ['view', '--port', port, '--view-port', '0', '--timeout-s', '30', ...args],
    {
      stdio: ['ignore', 'pipe', 'pipe'],
    },
  );
  let text = '';
  child.stderr.setEncoding('utf8');
  child.stderr.on('data', (chunk) => {
    text += chunk;
  });
  const url = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`no address after 60 s: ${text}`)), 60_000);
    child.stderr.on('data', () => {
      const found = /3D view: (http:\/\/\S+)/.exec(text);
      if (found) {
        clearTimeout(timer);
        resolve(found[1]);
      }
    });
    child.on('exit', (code) => reject(new Error(`hexapod view exited (${code}): ${text}`)));
  });
  return { child, url, stderr: () => text };
}
