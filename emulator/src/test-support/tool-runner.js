// The host tool `hexapod` against `./dev run --pty` (src/run.js), for tests that drive the
// tool as a user would: the tool built once, the runner started on a pseudo-terminal, the tool
// run (asynchronously, so the runner keeps emulating) with its standard input scripted.

import { execFileSync, spawn } from 'node:child_process';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

import { DEFAULT_ELF } from '../chip/board.js';

export const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
const RUNNER = join(REPO, 'emulator', 'src', 'run.js');

/** The tool's binary, built once (the path cargo reports). */
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
 * Starts `run.js --pty` with `args` (e.g. ['--no-view']); resolves, once the pty's path is
 * printed, to `{ runner, port, log }` (`log()`: its standard error so far; a `3D view: URL`
 * line when the view is on).
 */
export async function startRunner(args) {
  const runner = spawn(process.execPath, [RUNNER, '--pty', ...args, '--elf', DEFAULT_ELF], {
    stdio: ['ignore', 'ignore', 'pipe'],
  });
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

/** Runs the tool with `args` in `cwd`, `input` on its standard input; resolves to its outcome. */
export function runTool(tool, args, { cwd, input = '' }) {
  return new Promise((resolve) => {
    const child = spawn(tool, args, { cwd });
    let stdout = '';
    let stderr = '';
    child.stdout.on('data', (d) => {
      stdout += d;
    });
    child.stderr.on('data', (d) => {
      stderr += d;
    });
    child.stdin.on('error', () => {}); // a tool that exits before reading it all
    child.stdin.end(input);
    child.on('close', (status) => resolve({ status, stdout, stderr }));
  });
}
