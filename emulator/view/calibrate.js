// The page's guided calibration (docs/geometry-and-calibration.md, "Calibration"; the same
// flow as `hexapod calibrate` in a terminal): servo by servo, the arm brought level with
// `servo N us` steps (buttons, or the keys + - [ ] Enter q while the panel has focus), the trim
// taken from that pulse (eq. 13 / 14: W = W0 + d r (alpha - alpha0), so the trim of an arm level
// at W is W + d r alpha0); the six trims set; the platform checked at home and at a few poses
// against a level and a ruler; then `save`, and the trims to put in the build file.
//
// It talks to the board as the page's terminal does: whole lines by POST /uart, the board's
// output from the event stream's `uart` events (a connection of its own), each line's reply
// being the next final reply (`ok` or `error:...`) that does not close a listing the view
// asked for (`geometry`, `config`). The board's settings come from the view's listings.
// Quitting (or a refusal) puts back what was changed: pulses, trims, the platform at home;
// nothing is saved. Every pulse sent is within the servo's limits. Pulses in us, angles in
// degrees.

const SMALL_STEP_US = 1;
const BIG_STEP_US = 10;
/** The check poses (x y z mm, roll pitch yaw degrees) and what to measure at each. */
const CHECKS = [
  {
    pose: '0 0 0 0 0 0',
    measure:
      'home: a spirit level on the platform along x, then along y: the bubble within its ' +
      'marks (level within about 0.5°); note the platform’s height above the base plate',
  },
  {
    pose: '0 0 10 0 0 0',
    measure:
      '10 mm up: the ruler shows the platform 10 mm higher than at home (within 1 mm), still level',
  },
  {
    pose: '0 0 0 5 0 0',
    measure: 'roll 5°: tilted about the x axis by 5° (within 1°), not about y',
  },
  {
    pose: '0 0 0 0 5 0',
    measure: 'pitch 5°: tilted about the y axis by 5° (within 1°), not about x',
  },
  {
    pose: '0 0 0 0 0 10',
    measure: 'yaw 10°: turned 10° about the vertical, level and at the home height',
  },
];
/** The panel's words. */
const WORDS = {
  intro:
    'Servos powered, rods unhooked from the arms. Each servo in turn: bring its arm level ' +
    '(horizontal), then “level”. Then hook up the rods and check a few poses. Quit puts ' +
    'everything back, unsaved. Do not type in the terminal meanwhile.',
  servo: (n, alpha0) =>
    `Servo ${n}: bring its arm level (a level on the arm). Its home angle alpha0 is ` +
    `${alpha0.toFixed(3)}°; the trim is worked out from level for you.`,
  limit: (n, min, max) =>
    `servo ${n} kept within its limits ${min.toFixed(2)}..${max.toFixed(2)} µs`,
  trimOutside: (n, trim) =>
    `servo ${n}: that makes trim_us ${trim.toFixed(2)}, outside its limits: remount the arm a ` +
    'spline tooth closer to level',
  trims: (trims) =>
    `Trims set (not saved yet): ${trims.map((t) => t.toFixed(2)).join(' ')} µs. Hook the rods ` +
    'to the arms now, then check each pose.',
  check: (c, h0) =>
    `pose ${c.pose}: ${c.measure}${c.pose === '0 0 0 0 0 0' ? ` (rod joints h0 = ${h0.toFixed(1)} mm above the servo shafts)` : ''}. ` +
    'If it is off: an arm a tooth off, a servo turning the wrong way (servoN.dir), the rate or the geometry.',
  refused: (line, reply) => `${line}: the board refused it (${reply})`,
  saved: 'Saved on the board. The trims for your build file (or `hexapod pull --port PORT`):',
  stopped: 'Calibration stopped: pulses and trims as they were, platform at home, nothing saved.',
  failed: (why) => `Calibration stopped: ${why}. What it changed was put back where it could be.`,
  waiting: 'waiting for the board’s geometry and config listings…',
};

const FINAL = /^(ok|error:)/;
const LISTING_START = /^# (layout|frame_hz):/;

/** Lines to and replies from the board over the page's link. */
class BoardLines {
  constructor() {
    this.partial = '';
    this.listing = false;
    this.waiter = null;
    this.geometry = null;
    this.config = null;
    const events = new EventSource('/events');
    events.addEventListener('uart', (event) => this.output(JSON.parse(event.data).text));
    events.addEventListener('geometry', (event) => {
      this.geometry = JSON.parse(event.data);
    });
    events.addEventListener('config', (event) => {
      this.config = JSON.parse(event.data);
    });
  }

  output(text) {
    const lines = (this.partial + text).split('\n');
    this.partial = lines.pop();
    for (const raw of lines) {
      const line = raw.replace(/\r/g, '').replace(/^(> )+/, '');
      if (LISTING_START.test(line)) {
        this.listing = true;
      } else if (FINAL.test(line)) {
        const theirs = this.listing;
        this.listing = false;
        if (!theirs && this.waiter) {
          this.waiter.done(this.waiter.data, line);
          this.waiter = null;
        }
      } else if (this.waiter && line.startsWith('# ')) {
        this.waiter.data.push(line);
      }
    }
  }

  /** Sends a line; resolves to `{ ok, reply, data }` once its final reply has come. */
  async request(line) {
    const reply = new Promise((resolve, reject) => {
      const timer = setTimeout(() => {
        this.waiter = null;
        reject(new Error(`no reply to “${line}”`));
      }, 30_000);
      this.waiter = {
        data: [],
        done: (data, last) => {
          clearTimeout(timer);
          resolve({ ok: last === 'ok', reply: last, data });
        },
      };
    });
    const response = await fetch('/uart', {
      method: 'POST',
      headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ line }),
    });
    if (!response.ok) {
      this.waiter = null;
      throw new Error((await response.text()).trim());
    }
    return reply;
  }

  /** A request the board must accept. */
  async must(line) {
    const outcome = await this.request(line);
    if (!outcome.ok) {
      throw new Error(WORDS.refused(line, outcome.reply));
    }
    return outcome;
  }

  /** Waits until `status` says the platform is not moving. */
  async settle() {
    for (let i = 0; i < 600; i++) {
      const { data } = await this.must('status');
      const state = data.find((l) => l.startsWith('# state:')) ?? '';
      if (!/^# state: (moving|returning|going)/.test(state)) {
        return;
      }
      await new Promise((resolve) => setTimeout(resolve, 100));
    }
    throw new Error('the platform kept moving');
  }
}

const round2 = (us) => Math.round(us * 100) / 100;

class CalibrationPanel {
  constructor(container) {
    this.board = new BoardLines();
    this.container = container;
    this.busy = false;
    this.answer = null; // resolves the current question with a key
    this.keys = 0;
    container.innerHTML = `
      <h2>Calibration <small>guided, servo by servo</small></h2>
      <p class="calibrate-text" id="calibrate-text">${WORDS.intro}</p>
      <p class="calibrate-pulse" id="calibrate-pulse"></p>
      <div class="calibrate-keys" id="calibrate-keys" hidden>
        <button data-key="[">−10 µs</button><button data-key="-">−1 µs</button>
        <button data-key="+">+1 µs</button><button data-key="]">+10 µs</button>
        <button data-key="Enter" class="accept">level</button>
      </div>
      <div class="calibrate-next" id="calibrate-next" hidden>
        <button data-key="Enter" class="accept">good, next</button>
      </div>
      <button id="calibrate-start">start calibration</button>
      <button id="calibrate-quit" data-key="q" hidden>quit</button>
      <pre id="calibrate-result" hidden></pre>`;
    this.$ = (id) => /** @type {HTMLElement} */ (container.querySelector(`#${id}`));
    container.tabIndex = 0;
    container.dataset.stage = 'idle';
    container.addEventListener('click', (event) => {
      const key = /** @type {HTMLElement | null} */ (
        /** @type {HTMLElement} */ (event.target).closest('[data-key]')
      );
      if (key) {
        this.key(key.dataset.key);
      }
    });
    container.addEventListener('keydown', (event) => {
      if (['+', '-', '[', ']', 'Enter', 'q'].includes(event.key) && this.answer) {
        event.preventDefault();
        this.key(event.key);
      }
    });
    this.$('calibrate-start').addEventListener('click', () => this.run());
  }

  key(key) {
    if (this.answer && !this.busy) {
      const answer = this.answer;
      this.answer = null;
      this.keys += 1;
      this.container.dataset.keys = String(this.keys); // keys taken, for a test to follow
      answer(key);
    }
  }

  /** Shows `text`, the buttons of `stage`, and waits for a key. */
  ask(stage, text) {
    this.container.dataset.stage = stage;
    this.$('calibrate-text').textContent = text;
    this.$('calibrate-keys').hidden = stage !== 'servo';
    this.$('calibrate-next').hidden = stage !== 'check';
    this.container.dataset.busy = 'false';
    return new Promise((resolve) => {
      this.answer = resolve;
    });
  }

  async step(work) {
    this.busy = true;
    this.container.dataset.busy = 'true';
    try {
      return await work();
    } finally {
      this.busy = false;
      this.container.dataset.busy = 'false';
    }
  }

  async run() {
    const board = this.board;
    if (!board.geometry || !board.config) {
      this.$('calibrate-text').textContent = WORDS.waiting;
      return;
    }
    const servos = board.config.servos.map((s) => ({ ...s }));
    const legs = board.geometry.legs;
    this.changed = { driven: [], trimsSet: false, servos };
    this.$('calibrate-start').hidden = true;
    this.$('calibrate-quit').hidden = false;
    this.$('calibrate-result').hidden = true;
    let outcome;
    try {
      outcome = await this.flow(servos, legs, board.geometry.homeHeightMm);
    } catch (error) {
      outcome = { error };
    }
    this.$('calibrate-keys').hidden = true;
    this.$('calibrate-next').hidden = true;
    this.$('calibrate-quit').hidden = true;
    this.$('calibrate-start').hidden = false;
    this.$('calibrate-pulse').textContent = '';
    if (outcome.trims) {
      this.container.dataset.stage = 'saved';
      this.$('calibrate-text').textContent = WORDS.saved;
      const result = this.$('calibrate-result');
      result.textContent = outcome.trims
        .map((t, i) => `[servo${i + 1}]\ntrim_us = ${t.toFixed(2)}`)
        .join('\n');
      result.hidden = false;
      return;
    }
    try {
      await this.step(() => this.putBack());
      this.$('calibrate-text').textContent = outcome.error
        ? WORDS.failed(outcome.error.message)
        : WORDS.stopped;
    } catch (error) {
      this.$('calibrate-text').textContent = WORDS.failed(error.message);
    }
    this.container.dataset.stage = 'stopped';
  }

  /** The flow; `{ trims }`, or `{}` when the user quit. */
  async flow(servos, legs, h0) {
    const board = this.board;
    await this.step(async () => {
      // Home first; with pulses set by `servo` at no pose, each servo to its trim first.
      if (!(await board.request('home')).ok) {
        for (const s of servos) {
          await board.must(`servo ${s.servo} ${s.trimUs}`);
        }
        await board.must('home');
      }
      await board.settle();
    });
    const trims = [];
    for (const s of servos) {
      const alpha0 = (legs[s.servo - 1].alpha0Deg * Math.PI) / 180;
      const sign = s.dir === 'reversed' ? -1 : 1;
      const within = (us) => round2(Math.min(Math.max(us, s.minUs), s.maxUs));
      let pulse = within(s.trimUs - sign * s.rateUsRad * alpha0);
      await this.step(() => this.drive(s.servo, pulse));
      let note = '';
      for (;;) {
        this.$('calibrate-pulse').textContent = `servo ${s.servo} at ${pulse.toFixed(2)} µs${note}`;
        const key = await this.ask('servo', WORDS.servo(s.servo, legs[s.servo - 1].alpha0Deg));
        note = '';
        if (key === 'q') {
          return {};
        }
        if (key === 'Enter') {
          const trim = round2(pulse + sign * s.rateUsRad * alpha0);
          if (trim < s.minUs || trim > s.maxUs) {
            note = ` — ${WORDS.trimOutside(s.servo, trim)}`;
            continue;
          }
          trims.push(trim);
          break;
        }
        const step = {
          '+': SMALL_STEP_US,
          '-': -SMALL_STEP_US,
          ']': BIG_STEP_US,
          '[': -BIG_STEP_US,
        }[key];
        const wanted = pulse + step;
        if (wanted < s.minUs || wanted > s.maxUs) {
          note = ` — ${WORDS.limit(s.servo, s.minUs, s.maxUs)}`;
        }
        if (within(wanted) !== pulse) {
          pulse = within(wanted);
          await this.step(() => this.drive(s.servo, pulse));
        }
      }
    }
    this.$('calibrate-pulse').textContent = '';
    await this.step(async () => {
      for (const [i, trim] of trims.entries()) {
        await board.must(`set servo${i + 1}.trim_us ${trim}`);
        this.changed.trimsSet = true;
      }
      await board.must('home');
      await board.settle();
    });
    let text = WORDS.trims(trims);
    for (const check of CHECKS) {
      const line = `pose ${check.pose}`;
      const moved = await this.step(async () => {
        const outcome = await board.request(line);
        if (outcome.ok) {
          await board.settle();
        }
        return outcome;
      });
      text = moved.ok
        ? `${text ? `${text}\n\n` : ''}${WORDS.check(check, h0)}`
        : `${text ? `${text}\n\n` : ''}${WORDS.refused(line, moved.reply)}`;
      if (!moved.ok) {
        continue;
      }
      const key = await this.ask('check', text);
      text = '';
      if (key === 'q') {
        return {};
      }
    }
    await this.step(async () => {
      await board.must('home');
      await board.settle();
      await board.must('save');
    });
    return { trims };
  }

  async drive(servo, pulse) {
    this.changed.driven[servo - 1] = true;
    await this.board.must(`servo ${servo} ${pulse}`);
  }

  /** Puts back the trims and pulses, the platform at home. */
  async putBack() {
    const board = this.board;
    const { driven, trimsSet, servos } = this.changed;
    await board.settle();
    if (trimsSet) {
      await board.must('home');
      await board.settle();
      for (const s of servos) {
        await board.must(`set servo${s.servo}.trim_us ${s.trimUs}`);
      }
      this.changed.trimsSet = false;
    }
    for (const s of servos) {
      if (driven[s.servo - 1]) {
        await board.must(`servo ${s.servo} ${s.trimUs}`);
      }
    }
    this.changed.driven = [];
    await board.must('home');
    await board.settle();
  }
}

const container = document.getElementById('calibrate');
if (container) {
  new CalibrationPanel(container);
}
