// The page's jog panel: six sliders (x y z in mm, roll pitch yaw in degrees), keys, home and
// stop, each sent to the board as its own move commands (`move axis=value ...`, `home`,
// `stop`: docs/commands.md) through POST /command, on the view's own link, so they never show
// in anyone's terminal. The board plans every move itself (a straight line at its speed_* and
// accel_* settings, checked against its servo limits before it starts), so a jog is as smooth
// as any move and never a jump; a refused one (out of reach, e-stop) is shown in the board's
// words and its slider goes back. One command is in flight at a time: slider changes made
// meanwhile are sent together when its reply comes. While nobody touches them the sliders
// follow the platform's pose (the forward kinematics of the pins). Each slider's range is the
// board's own reach along its axis (`limits`, asked again whenever the board's listings change),
// or a modest default until it has answered.
//
// Keys (while the typing line does not have the focus): arrows x and y, Page Up/Down z, q/a
// roll, w/s pitch, e/d yaw (1 mm or degree a press, 5 with Shift), h home, Esc or space stop.

export const AXES = [
  { name: 'x', unit: 'mm', range: 30 },
  { name: 'y', unit: 'mm', range: 30 },
  { name: 'z', unit: 'mm', range: 20 },
  { name: 'roll', unit: '°', range: 15 },
  { name: 'pitch', unit: '°', range: 15 },
  { name: 'yaw', unit: '°', range: 25 },
];

/** key -> [axis, direction]. */
const KEYS = {
  ArrowRight: ['x', 1],
  ArrowLeft: ['x', -1],
  ArrowUp: ['y', 1],
  ArrowDown: ['y', -1],
  PageUp: ['z', 1],
  PageDown: ['z', -1],
  q: ['roll', 1],
  a: ['roll', -1],
  w: ['pitch', 1],
  s: ['pitch', -1],
  e: ['yaw', 1],
  d: ['yaw', -1],
};

/** `limits`' line for one direction: `# x-: 39.541 mm to x=-39.541 (...)`. */
const REACH = /^# (x|y|z|roll|pitch|yaw)([+-]): \S+ (?:mm|deg) to \w+=(-?\d+(?:\.\d+)?)/;

/** After a slider or key is touched, it stops following the pose for this long, ms. */
const HANDS_OFF_MS = 1500;

/** Sends one line on the view's own link: resolves to `{ reply, data }`. */
export async function command(line) {
  const response = await fetch('/command', {
    method: 'POST',
    headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ line }),
  });
  if (!response.ok) {
    return { reply: `error:page ${(await response.text()).trim()}`, data: [] };
  }
  return response.json();
}

export class JogPanel {
  /**
   * @param {object} parts
   * @param {HTMLElement} parts.container where the sliders go
   * @param {HTMLElement} parts.note where the board's refusals show
   * @param {HTMLElement} parts.home
   * @param {HTMLElement} parts.stop
   */
  constructor({ container, note, home, stop }) {
    this.note = note;
    this.sliders = new Map();
    this.values = new Map();
    /** Axes changed since the last command: sent with the next one. */
    this.dirty = new Set();
    /** The last values the board accepted, per axis (a refused slider goes back to it). */
    this.accepted = new Map(AXES.map(({ name }) => [name, 0]));
    this.inFlight = false;
    this.askingLimits = false;
    this.touchedAt = 0;
    for (const axis of AXES) {
      const row = document.createElement('label');
      row.className = 'jog-axis';
      const name = document.createElement('span');
      name.textContent = axis.name;
      const slider = document.createElement('input');
      Object.assign(slider, {
        type: 'range',
        min: String(-axis.range),
        max: String(axis.range),
        step: '0.5',
        value: '0',
      });
      slider.id = `jog-${axis.name}`;
      slider.dataset.axis = axis.name;
      const value = document.createElement('output');
      value.textContent = `0 ${axis.unit}`;
      row.append(name, slider, value);
      container.append(row);
      this.sliders.set(axis.name, slider);
      this.values.set(axis.name, value);
      slider.addEventListener('input', () => this.changed(axis.name));
    }
    home.addEventListener('click', () => this.home());
    stop.addEventListener('click', () => this.stop());
    document.addEventListener('keydown', (event) => this.key(event));
  }

  /**
   * Asks the board how far each axis reaches (`limits`) and makes that each slider's range, to
   * the half step inside it.
   */
  async refreshLimits() {
    if (this.askingLimits) {
      return;
    }
    this.askingLimits = true;
    let answer;
    try {
      answer = await command('limits');
    } catch {
      answer = { reply: 'error:page', data: [] };
    } finally {
      this.askingLimits = false;
    }
    if (answer.reply !== 'ok') {
      return; // (busy moving, say: the ranges stay as they were)
    }
    for (const line of answer.data) {
      const match = REACH.exec(line);
      if (!match) {
        continue;
      }
      const [, axis, side, value] = match;
      const slider = this.sliders.get(axis);
      if (side === '-') {
        slider.min = String(Math.ceil(Number(value) * 2) / 2);
      } else {
        slider.max = String(Math.floor(Number(value) * 2) / 2);
      }
    }
  }

  /** Sets a slider (clamped to its range) and its readout. */
  set(axis, value) {
    const slider = this.sliders.get(axis);
    const clamped = Math.min(Math.max(value, Number(slider.min)), Number(slider.max));
    slider.value = String(clamped);
    const unit = AXES.find((a) => a.name === axis).unit;
    this.values.get(axis).textContent = `${Number(slider.value).toFixed(1)} ${unit}`;
  }

  changed(axis) {
    this.touchedAt = performance.now();
    this.set(axis, Number(this.sliders.get(axis).value));
    this.dirty.add(axis);
    this.flush();
  }

  key(event) {
    const target = /** @type {HTMLElement} */ (event.target);
    if (target.closest?.('input:not([type=range]), textarea, select, [contenteditable]')) {
      return; // typing a line
    }
    if (event.key === 'h' && !event.ctrlKey && !event.metaKey) {
      event.preventDefault();
      this.home();
      return;
    }
    if (event.key === 'Escape' || event.key === ' ') {
      event.preventDefault();
      this.stop();
      return;
    }
    const jog = KEYS[event.key.length === 1 ? event.key.toLowerCase() : event.key];
    if (!jog || event.ctrlKey || event.metaKey || event.altKey) {
      return;
    }
    event.preventDefault();
    const [axis, direction] = jog;
    const step = event.shiftKey ? 5 : 1;
    this.set(axis, Number(this.sliders.get(axis).value) + direction * step);
    this.changed(axis);
  }

  /** Sends the changed axes in one `move`, unless a command is in flight. */
  async flush() {
    if (this.inFlight || this.dirty.size === 0) {
      return;
    }
    const axes = [...this.dirty];
    this.dirty.clear();
    const values = axes.map((axis) => [axis, Number(this.sliders.get(axis).value)]);
    const line = `move ${values.map(([axis, v]) => `${axis}=${v}`).join(' ')}`;
    const answer = await this.send(line);
    if (answer.reply === 'ok') {
      for (const [axis, v] of values) {
        this.accepted.set(axis, v);
      }
    } else {
      for (const [axis] of values) {
        if (!this.dirty.has(axis)) {
          this.set(axis, this.accepted.get(axis));
        }
      }
    }
    this.flush();
  }

  async home() {
    this.dirty.clear();
    const answer = await this.send('home');
    if (answer.reply === 'ok') {
      for (const { name } of AXES) {
        this.set(name, 0);
        this.accepted.set(name, 0);
      }
      this.touchedAt = performance.now();
    }
  }

  async stop() {
    this.dirty.clear();
    this.touchedAt = 0; // the sliders follow the pose where it stopped
    await this.send('stop');
  }

  /** One command, its refusal shown in the board's words. */
  async send(line) {
    this.inFlight = true;
    let answer;
    try {
      answer = await command(line);
    } catch (error) {
      answer = { reply: `error:page ${error.message}`, data: [] };
    }
    this.inFlight = false;
    this.note.textContent = answer.reply === 'ok' ? '' : `${line}: ${answer.reply}`;
    this.note.dataset.reply = answer.reply.split(' ')[0];
    return answer;
  }

  /** The platform's pose (x y z mm, roll pitch yaw deg): the sliders follow it when idle. */
  showPose(pose) {
    if (this.inFlight || this.dirty.size > 0) {
      return;
    }
    if (performance.now() - this.touchedAt < HANDS_OFF_MS) {
      return;
    }
    AXES.forEach(({ name }, i) => {
      // Half-step sliders: the nearest one (its readout says the pose to 0.1).
      this.set(name, Math.round(pose[i] * 2) / 2);
      this.accepted.set(name, Number(this.sliders.get(name).value));
    });
  }
}
