// The host core's computation, for comparing with what the firmware puts on its pins.
//
// `host-tests/examples/pulse_reference.rs` runs `kinematics-core` built for the host (libm):
// given a layout, six servo mappings and poses (mm, degrees), it answers with arm angles and
// pulse widths, or the error the core gives. The firmware computes the same with the RP2040
// boot ROM's float routines; the end-to-end tests require the two to agree within one PWM
// count. The program is built once per process (`cargo build`, a no-op when `cargo test` has
// built it already) and then run directly, one batch of requests per call.

import { execFileSync, spawnSync } from 'node:child_process';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const REPO = join(dirname(fileURLToPath(import.meta.url)), '..', '..', '..');
const EXAMPLE = 'pulse_reference';

let cachedBinary = null;

/** Builds the reference program (once per process) and returns its path. */
export function buildHostReference() {
  if (cachedBinary) {
    return cachedBinary;
  }
  const output = execFileSync(
    'cargo',
    ['build', '--quiet', '-p', 'host-tests', '--example', EXAMPLE, '--message-format=json'],
    {
      cwd: REPO,
      encoding: 'utf8',
      maxBuffer: 64 * 1024 * 1024,
      stdio: ['ignore', 'pipe', 'inherit'],
    },
  );
  for (const line of output.split('\n')) {
    if (!line.startsWith('{')) {
      continue;
    }
    const message = JSON.parse(line);
    if (
      message.reason === 'compiler-artifact' &&
      message.target?.name === EXAMPLE &&
      message.executable
    ) {
      cachedBinary = message.executable;
    }
  }
  if (!cachedBinary) {
    throw new Error(`cargo build did not report the ${EXAMPLE} executable`);
  }
  return cachedBinary;
}

/** A setting's number as the reference takes it: `off` (or absent) is 0. */
function orZero(value) {
  const number = Number(value ?? 0);
  return Number.isFinite(number) ? number : 0;
}

/**
 * Settings as the reference takes them: the paired layout, six servos, the payload and the
 * pivot, in the units and names `set` uses. `servos[i]` is servo i + 1:
 * `{ trim_us, rate_us_rad, dir, min_us, max_us, torque_kgcm }`; `payload` (optional) is
 * `{ payload_g, payload_com_x_mm, payload_com_y_mm, payload_com_z_mm }`; `pivot` (optional)
 * `{ pivot_x_mm, pivot_y_mm, pivot_z_mm }`.
 */
/**
 * @param {{ layout: Record<string, number>, servos: Record<string, number | string>[],
 *   payload?: Record<string, number>, pivot?: Record<string, number> }} settings
 */
export function configLines({ layout, servos, payload = {}, pivot = {} }) {
  const l = layout;
  const p = payload;
  return [
    `pivot ${orZero(pivot.pivot_x_mm)} ${orZero(pivot.pivot_y_mm)} ${orZero(pivot.pivot_z_mm)}`,
    `layout ${l.base_radius_mm} ${l.base_half_angle_deg} ${l.platform_radius_mm} ${l.platform_half_angle_deg} ${l.arm_mm} ${l.rod_mm}`,
    ...servos.map(
      (s, i) => `servo ${i + 1} ${s.trim_us} ${s.rate_us_rad} ${s.dir} ${s.min_us} ${s.max_us}`,
    ),
    `payload ${orZero(p.payload_g)} ${orZero(p.payload_com_x_mm)} ${orZero(p.payload_com_y_mm)} ${orZero(p.payload_com_z_mm)}`,
    `ratings ${servos.map((s) => orZero(s.torque_kgcm)).join(' ')}`,
  ];
}

export class HostReference {
  constructor(binary = buildHostReference()) {
    this.binary = binary;
  }

  /** Runs request lines; returns one parsed answer per line. */
  run(requests) {
    const result = spawnSync(this.binary, [], {
      input: `${requests.join('\n')}\n`,
      encoding: 'utf8',
      maxBuffer: 256 * 1024 * 1024,
    });
    if (result.status !== 0) {
      throw new Error(`${this.binary} failed (${result.status}): ${result.stderr}`);
    }
    const answers = result.stdout
      .trim()
      .split('\n')
      .map((line) => JSON.parse(line));
    if (answers.length !== requests.length) {
      throw new Error(`${requests.length} requests, ${answers.length} answers`);
    }
    return answers;
  }

  /** Configures, then runs the rest; throws if the configuration is refused. */
  runWith(settings, requests) {
    const config = configLines(settings);
    const answers = this.run([...config, ...requests]);
    answers.slice(0, config.length).forEach((answer, i) => {
      if (!answer.ok) {
        throw new Error(`reference refused '${config[i]}': ${answer.error}`);
      }
    });
    return answers.slice(config.length);
  }

  /**
   * The core's solution for each pose (`[x, y, z, roll, pitch, yaw]`, mm and degrees) with
   * these settings: `{ ok: true, arm_deg, pulse_us }` or `{ ok: false, code, ... }`.
   */
  solve(settings, poses) {
    return this.runWith(
      settings,
      poses.map((pose) => `solve ${pose.join(' ')}`),
    );
  }

  /**
   * Not the core: the independent f64 reference (`host-tests`' chain of frames about the
   * pivot, each rod closure's numeric root, eq. 13, 14 in f64) for each pose:
   * `{ ok: true, arm_deg, pulse_us }` or `{ ok: false, code: 'unreachable' }`.
   */
  f64(settings, poses) {
    return this.runWith(
      settings,
      poses.map((pose) => `f64 ${pose.join(' ')}`),
    );
  }

  /** The core's geometry for these settings: `{ arm_mm, rod_mm, h0_mm, legs: [...] }`. */
  geometry(settings) {
    return this.runWith(settings, ['geometry'])[0];
  }

  /**
   * The holding torques (kgf cm, signed) of the settings' payload at each pose:
   * `{ ok: true, torque_kgcm }` or `{ ok: false, code, ... }`.
   */
  torques(settings, poses) {
    return this.runWith(
      settings,
      poses.map((pose) => `torque ${pose.join(' ')}`),
    );
  }

  /**
   * The pose six pulses correspond to (the core's forward kinematics from `start`, checked
   * with the IK): `{ ok: true, pose }` (mm, degrees) or `{ ok: false, code: 'no-pose', error }`.
   */
  forwardKinematics(settings, pulses, start = [0, 0, 0, 0, 0, 0]) {
    return this.runWith(settings, [`fk ${pulses.join(' ')} ${start.join(' ')}`])[0];
  }

  /**
   * The reach along each axis-direction from `pose` (x- first), within the servo limits and,
   * with a payload and ratings, the ratings: `[{ axis, sense, distance, extreme, limit }]`
   * (mm or degrees; `limit: { kind: 'blocked' | 'range' | 'start', code, ... }`).
   */
  limits(settings, pose) {
    const [answer] = this.runWith(settings, [`limits ${pose.join(' ')}`]);
    if (!answer.ok) {
      throw new Error(`reference limits: ${JSON.stringify(answer)}`);
    }
    return answer.reaches;
  }
}
