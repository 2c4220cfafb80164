// The host tool `hexapod` (cli/) for tests that run it against the emulated board: its binary
// built once (the path cargo reports), and `./dev run --pty --no-view` started with the path of
// its pseudo-terminal (the board's USB port, or UART0 with `--uart`). Used by
// test/view-board.test.js.

import { execFileSync, spawn } from 'node:child_process';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { DEFAULT_ELF } from '../chip/board.js';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
const RUNNER = join(REPO, 'emulator', 'src', 'run.js');

/** Builds the tool; returns its executable's path. */
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
 * Starts the emulated board with a link on a pseudo-terminal and no view of its own. Returns
 * `{ runner, port, log }`: the child, the pty's path, and `log()`: its stderr so far (with the
 * `servos us: ...` lines of the pins it measures).
 */
export async function startPtyRunner(args = []) {
  const runner = spawn(
    process.execPath,
    [RUNNER, '--pty', '--no-view', '--elf', DEFAULT_ELF, ...args],
    {
      stdio: ['ignore', 'ignore', 'pipe'],
    },
  );
  let text = '';
  runner.stderr.setEncoding('utf8');
  runner.stderr.on('data', (chunk) => {
    text += chunk;
  });
  const port = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error(`no pty after 60 s: ${text}`)), 60_000);
    const look = () => {
      const found = text.match(/is on (\/\S+)/);
      if (found) {
        clearTimeout(timer);
        runner.stderr.off('data', look);
        resolve(found[1]);
      }
    };
    runner.stderr.on('data', look);
    runner.on('exit', (code) => reject(new Error(`the runner exited (${code}): ${text}`)));
  });
  return { runner, port, log: () => text };
}

/**
 * Starts `hexapod view --port PORT --view-port 0`; resolves to `{ child, url, stderr() }` once
 * it prints the page's address.
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
