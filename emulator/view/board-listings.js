// Reads the board's own listings out of what it sends on its serial link, line by line:
// `geometry` (layout, arm and rod lengths in mm, home height in mm, per leg the shaft centre b
// and platform joint p in mm, the arm-plane angle beta and home arm angle alpha0 in degrees)
// and `config` (every `# name: value` setting; per servo trim, rate in us/rad, direction,
// limits in us, torque rating in kgf cm and speed rating in s per 60 degrees). The 3D view draws from these, so it shows the
// build the firmware uses, not the documented defaults. Whoever asked for the listing (a user,
// the view), it is read the same way; a listing counts only once its final `ok` has arrived,
// so a refused or cut one changes nothing. Plain JavaScript with no imports: the Node view server
// (emulator/src/view-server/) and the page itself (for `hexapod view`, whose server passes the
// board's lines on as they are) read listings with this one reader.

const NUMBER = String.raw`[-+]?\d+(?:\.\d+)?`;
const VECTOR = String.raw`\((${NUMBER}), (${NUMBER}), (${NUMBER})\)`;

const LAYOUT = /^# layout: (.*)$/;
const ARM = new RegExp(String.raw`^# arm_mm \(a\): (${NUMBER})$`);
const ROD = new RegExp(String.raw`^# rod_mm \(s\): (${NUMBER})$`);
const HOME_HEIGHT = new RegExp(String.raw`^# home_height_mm \(h0\): (${NUMBER})$`);
const LEG = new RegExp(
  String.raw`^# leg ([1-6]): b_mm=${VECTOR} p_mm=${VECTOR} beta_deg=(${NUMBER}) alpha0_deg=(${NUMBER})$`,
);
/** `config`'s first line: the listing starts with the frame rate. */
const CONFIG_START = /^# frame_hz: (\d+)$/;
const SETTING = /^# ([a-z][a-z0-9_.]*): (\S+)$/;
const SERVO = new RegExp(
  String.raw`^# servo([1-6]): trim_us=(${NUMBER}) rate_us_rad=(${NUMBER}) dir=(normal|reversed) ` +
    String.raw`min_us=(${NUMBER}) max_us=(${NUMBER}) torque_kgcm=(off|${NUMBER})` +
    String.raw`(?: speed_s_60deg=(off|${NUMBER}))?$`,
);
const OK = /^ok\b/;
const ERROR = /^error:/;

/**
 * Feed it every line the board sends (without CR/LF); `line()` returns a finished listing when
 * one ends with `ok`:
 * - `{ kind: 'geometry', geometry: { layout, armMm, rodMm, homeHeightMm, legs: [{ leg, baseMm:
 *   [x, y, z], platformMm: [x, y, z], betaDeg, alpha0Deg }] } }` (legs 1..6 in order);
 * - `{ kind: 'config', config: { settings: { frame_hz: '50', ... }, servos: [{ servo, trimUs,
 *   rateUsRad, dir: 'normal' | 'reversed', minUs, maxUs, torqueKgcm, speedS60deg }] } }` (servos
 *   1..6 in order; torqueKgcm, speedS60deg null when the servo is not rated);
 * otherwise null. Lines that belong to neither (echo, prompts, notices) are skipped.
 */
export class ListingReader {
  constructor() {
    this.open = null; // the listing being read: { kind, ... }
  }

  line(text) {
    let match;
    if ((match = LAYOUT.exec(text))) {
      this.open = { kind: 'geometry', layout: match[1], legs: [] };
      return null;
    }
    if ((match = CONFIG_START.exec(text))) {
      this.open = { kind: 'config', settings: { frame_hz: match[1] }, servos: [] };
      return null;
    }
    if (this.open === null) {
      return null;
    }
    if (OK.test(text)) {
      const done = this.finish(this.open);
      this.open = null;
      return done;
    }
    if (ERROR.test(text)) {
      this.open = null;
      return null;
    }
    if (this.open.kind === 'geometry') {
      this.geometryLine(this.open, text);
    } else {
      this.configLine(this.open, text);
    }
    return null;
  }

  geometryLine(open, text) {
    let match;
    if ((match = ARM.exec(text))) {
      open.armMm = Number(match[1]);
    } else if ((match = ROD.exec(text))) {
      open.rodMm = Number(match[1]);
    } else if ((match = HOME_HEIGHT.exec(text))) {
      open.homeHeightMm = Number(match[1]);
    } else if ((match = LEG.exec(text))) {
      const n = match.slice(2).map(Number);
      open.legs[Number(match[1]) - 1] = {
        leg: Number(match[1]),
        baseMm: n.slice(0, 3),
        platformMm: n.slice(3, 6),
        betaDeg: n[6],
        alpha0Deg: n[7],
      };
    }
  }

  configLine(open, text) {
    let match;
    if ((match = SERVO.exec(text))) {
      open.servos[Number(match[1]) - 1] = {
        servo: Number(match[1]),
        trimUs: Number(match[2]),
        rateUsRad: Number(match[3]),
        dir: match[4],
        minUs: Number(match[5]),
        maxUs: Number(match[6]),
        torqueKgcm: match[7] === 'off' ? null : Number(match[7]),
        speedS60deg: match[8] === undefined || match[8] === 'off' ? null : Number(match[8]),
      };
    } else if ((match = SETTING.exec(text))) {
      open.settings[match[1]] = match[2];
    }
  }

  /** The finished listing, or null if lines are missing (a notice cut into it, say). */
  finish(open) {
    const complete = (list) => Array.from(list).filter(Boolean).length === 6; // no holes
    if (open.kind === 'geometry') {
      const { layout, armMm, rodMm, homeHeightMm, legs } = open;
      if ([armMm, rodMm, homeHeightMm].some((v) => v === undefined) || !complete(legs)) {
        return null;
      }
      return { kind: 'geometry', geometry: { layout, armMm, rodMm, homeHeightMm, legs } };
    }
    if (!complete(open.servos)) {
      return null;
    }
    return { kind: 'config', config: { settings: open.settings, servos: open.servos } };
  }
}
