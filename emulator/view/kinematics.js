// The page's kinematics: loads view-kinematics.wasm (the project's Rust kinematics-core,
// compiled to WebAssembly) and turns what the pins carry into what a real platform would do:
// pulse widths (us) -> arm angles (deg) -> the platform pose by forward kinematics (mm, deg) and
// the points to draw (base frame, mm). No kinematics is computed in JavaScript.

/** What `view_solve` answers (view-kinematics `Status`). */
export const STATUS = ['solved', 'no geometry', 'no servo settings', 'no solution', 'no pulse'];
/** Why `view_build` refused a geometry (its codes 1..6). */
const BUILD_ERRORS = [
  null,
  'a leg is missing',
  'a coordinate is not finite',
  'a length is not positive',
  'no home height (eq. 10)',
  'the legs disagree on the home height',
  'the home pose is unreachable (eq. 9)',
];

export class Kinematics {
  /** Loads and instantiates the WebAssembly module. */
  static async load(url = '/view-kinematics.wasm') {
    const response = await fetch(url);
    if (!response.ok) {
      throw new Error(`${url}: ${response.status} ${(await response.text()).trim()}`);
    }
    const { instance } = await WebAssembly.instantiateStreaming(response, {});
    return new Kinematics(instance.exports);
  }

  constructor(wasm) {
    this.wasm = wasm;
    this.hasGeometry = false;
  }

  /**
   * The board's `geometry` listing (board-listings.js). Returns null, or why the core refused
   * it. Points to draw: `base` (b_i), `platform` (p_i, platform frame), `homeHeightMm` (h0 as the
   * core derives it), `alpha0Deg` (per leg, as the core derives it).
   */
  setGeometry(geometry) {
    for (const leg of geometry.legs) {
      this.wasm.view_set_leg(leg.leg, ...leg.baseMm, ...leg.platformMm, leg.betaDeg);
    }
    const code = this.wasm.view_build(geometry.armMm, geometry.rodMm);
    this.hasGeometry = code === 0;
    if (code !== 0) {
      const leg = this.wasm.view_error_leg();
      return `${BUILD_ERRORS[code] ?? `error ${code}`}${leg ? ` (leg ${leg})` : ''}`;
    }
    return null;
  }

  /** Derived from the geometry by the core: h0 (mm) and each leg's alpha0 (deg). */
  derived() {
    return {
      homeHeightMm: this.wasm.view_home_height_mm(),
      alpha0Deg: [1, 2, 3, 4, 5, 6].map((leg) => this.wasm.view_alpha0_deg(leg)),
      base: [1, 2, 3, 4, 5, 6].map((leg) => [0, 1, 2].map((k) => this.wasm.view_base_mm(leg, k))),
    };
  }

  /**
   * The board's `config` listing's pivot (`pivot_x_mm` ...: the rotation centre, platform frame,
   * mm; 0 where the listing has none), so that the pose found is in the convention of the poses
   * the board is sent. Returns null, or why the core refused it.
   */
  setPivot(config) {
    const pivot = ['x', 'y', 'z'].map((axis) => Number(config.settings[`pivot_${axis}_mm`] ?? 0));
    return this.wasm.view_set_pivot(...pivot) === 0 ? null : `pivot ${pivot} refused`;
  }

  /** The board's `config` listing: the six servo mappings. Returns the servos refused. */
  setServos(config) {
    const refused = [];
    for (const s of config.servos) {
      const dir = s.dir === 'normal' ? 1 : -1;
      if (this.wasm.view_set_servo(s.servo, s.trimUs, s.rateUsRad, dir, s.minUs, s.maxUs) !== 0) {
        refused.push(s.servo);
      }
    }
    return refused;
  }

  /**
   * Six pulse widths (us; null for a pin without pulses) -> `{ status, armDeg, poseMm: [x, y,
   * z], poseDeg: [roll, pitch, yaw], tips, joints, originMm, iterations, rodErrorMm }`
   * (`originMm`: the platform frame's origin, base frame, where the plate goes; with a pivot
   * not `(x, y, h0 + z)`). After 'no solution' the pose and joints are the last ones found.
   */
  solve(widthsUs) {
    const w = widthsUs.map((v) => (v === null ? NaN : v));
    const status = STATUS[this.wasm.view_solve(...w)] ?? 'unknown';
    const legs = [1, 2, 3, 4, 5, 6];
    const point = (fn) => legs.map((leg) => [0, 1, 2].map((k) => fn(leg, k)));
    return {
      status,
      armDeg: legs.map((leg) => this.wasm.view_arm_deg(leg)),
      poseMm: [0, 1, 2].map((k) => this.wasm.view_pose(k)),
      poseDeg: [3, 4, 5].map((k) => this.wasm.view_pose(k)),
      tips: point(this.wasm.view_tip_mm),
      joints: point(this.wasm.view_joint_mm),
      originMm: [0, 1, 2].map((k) => this.wasm.view_origin_mm(k)),
      iterations: this.wasm.view_iterations(),
      rodErrorMm: this.wasm.view_rod_error_mm(),
    };
  }
}
