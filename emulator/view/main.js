// The live view's page: connects to its server's event stream (the emulator's,
// emulator/src/view-server/view-server.js, or the host tool's for a board on a cable,
// `hexapod view`), runs every pin update through the project's kinematics (kinematics.js,
// WebAssembly) and shows the result: the 3D picture (scene.js), the readout (pulses in us, arm
// angles in deg, the pose in mm and deg), the board's serial output (terminal.js) and the jog
// panel (jog.js). When the emulator (or the board's link) stops it says so and keeps the last
// picture. The board's listings come parsed (`geometry`, `config` events) or as the board's
// lines (`listing` events), read here with the same reader (board-listings.js).

import { ListingReader } from './board-listings.js';
import { JogPanel } from './jog.js';
import { Kinematics } from './kinematics.js';
import { PlatformScene } from './scene.js';
import { PageTerminal } from './terminal.js';

const $ = (id) => document.getElementById(id);
const AXES = ['x', 'y', 'z', 'roll', 'pitch', 'yaw'];

const state = {
  kinematics: null,
  geometry: null, // the board's geometry listing
  config: null, // the board's config listing
  geometryError: null,
  servosRefused: [],
  pins: null,
  hasPose: false,
  cameraSet: false,
  asking: new Set(),
  stopped: null,
  source: 'emulator',
};

const scene = new PlatformScene($('stage'));
const terminal = new PageTerminal({
  container: $('terminal'),
  form: $('send'),
  input: $('line'),
  note: $('send-note'),
});
const jog = new JogPanel({
  container: $('jog'),
  note: $('jog-note'),
  home: $('jog-home'),
  stop: $('jog-stop'),
});
const reader = new ListingReader();
buildPinRows();
for (const button of /** @type {NodeListOf<HTMLElement>} */ (
  document.querySelectorAll('[data-camera]')
)) {
  button.addEventListener('click', () => scene.setCamera(button.dataset.camera));
}

try {
  state.kinematics = await Kinematics.load();
} catch (error) {
  overlay(`cannot load the kinematics (view-kinematics.wasm): ${error.message}`);
}
connect();

function connect() {
  const events = new EventSource('/events');
  events.addEventListener('hello', (event) => {
    const hello = JSON.parse(event.data);
    state.source = hello.source ?? 'emulator';
    if (state.source === 'board') {
      $('title-source').textContent = `live view of the board on ${hello.port}`;
      document.title = `hexapod-fw · ${hello.port}`;
      $('clock-name').textContent = 'link up';
      $('how').textContent =
        "Drawn from the pulse widths the board reports (its `pulses` answer), through the board's " +
        "servo settings and the project's own forward kinematics (in WebAssembly). " +
        'Drag to orbit, scroll to zoom.';
    }
    state.stopped = null;
    linkState('live', 'live');
    overlay(null);
  });
  events.addEventListener('uart', (event) => terminal.write(JSON.parse(event.data).text));
  events.addEventListener('asking', (event) => {
    for (const name of JSON.parse(event.data).listings) {
      state.asking.add(name);
    }
    refresh();
  });
  events.addEventListener('geometry', (event) => gotGeometry(JSON.parse(event.data)));
  events.addEventListener('config', (event) => gotConfig(JSON.parse(event.data)));
  events.addEventListener('listing', (event) => {
    for (const line of JSON.parse(event.data).lines) {
      const listing = reader.line(line);
      if (listing?.kind === 'geometry') {
        gotGeometry(listing.geometry);
      } else if (listing?.kind === 'config') {
        gotConfig(listing.config);
      }
    }
  });
  events.addEventListener('pins', (event) => {
    state.pins = JSON.parse(event.data);
    refresh();
  });
  events.addEventListener('stopped', (event) => {
    state.stopped = JSON.parse(event.data).reason;
    showStopped();
  });
  events.addEventListener('error', () => {
    // The stream broke: the runner quit or crashed. EventSource retries on its own and a new
    // runner on the same port says hello again.
    state.stopped ??= 'connection to the emulator lost';
    showStopped();
  });
}

function gotGeometry(geometry) {
  state.geometry = geometry;
  state.asking.delete('geometry');
  applyGeometry();
  jog.refreshLimits(); // the reach changes with the geometry
}

function gotConfig(config) {
  state.config = config;
  state.asking.delete('config');
  applyConfig();
  jog.refreshLimits(); // ... and with the servos' limits
}

function showStopped() {
  if (state.source === 'board') {
    linkState('stopped', 'link stopped');
    overlay(
      `The link to the board stopped: ${state.stopped}. The picture shows the last pulses ` +
        'seen. Start hexapod view again; this page reconnects by itself.',
    );
    return;
  }
  linkState('stopped', 'emulator stopped');
  overlay(
    `The emulator stopped: ${state.stopped}. The picture shows the last pins seen. ` +
      'Start ./dev run again; this page reconnects by itself.',
  );
}

function linkState(kind, text) {
  const element = $('link-state');
  element.className = `state ${kind}`;
  element.textContent = text;
}

function overlay(text) {
  const element = $('overlay');
  element.hidden = text === null;
  element.textContent = text ?? '';
}

function applyGeometry() {
  const k = state.kinematics;
  if (!k || !state.geometry) {
    return;
  }
  state.geometryError = k.setGeometry(state.geometry);
  state.hasPose = false;
  const g = state.geometry;
  const derived = k.derived();
  const dl = $('geometry');
  dl.replaceChildren();
  const row = (name, value) => {
    const dt = document.createElement('dt');
    dt.textContent = name;
    const dd = document.createElement('dd');
    dd.textContent = value;
    dl.append(dt, dd);
  };
  row('layout', g.layout.split(' ')[0]);
  row('arm a', `${g.armMm.toFixed(3)} mm`);
  row('rod s', `${g.rodMm.toFixed(3)} mm`);
  row('home h0', `${g.homeHeightMm.toFixed(3)} mm (core: ${derived.homeHeightMm.toFixed(3)})`);
  row('alpha0', `${g.legs[0].alpha0Deg.toFixed(3)}° (core: ${derived.alpha0Deg[0].toFixed(3)}°)`);
  if (state.geometryError === null) {
    scene.setGeometry({
      base: derived.base,
      platform: g.legs.map((leg) => leg.platformMm),
      betaDeg: g.legs.map((leg) => leg.betaDeg),
      armMm: g.armMm,
      homeHeightMm: derived.homeHeightMm,
    });
    if (!state.cameraSet) {
      state.cameraSet = true;
      scene.setCamera(new URLSearchParams(location.search).get('camera') ?? 'iso');
    }
  }
  refresh();
}

function applyConfig() {
  if (state.kinematics && state.config) {
    state.servosRefused = state.kinematics.setServos(state.config);
    state.kinematics.setPivot(state.config);
    const hz = state.config.settings.frame_hz;
    $('frame-rate').textContent = hz ? `frame_hz ${hz}` : '';
  }
  refresh();
}

/** Runs the latest pins through the kinematics and shows everything. */
function refresh() {
  const pins = state.pins;
  if (!pins) {
    return;
  }
  $('emulated-time').textContent =
    `${(pins.nanos / 1e9).toFixed(1)} s` +
    (pins.rateHz ? `, ${pins.rateHz.toFixed(0)} updates/s` : '');
  const widthsUs = pins.widthNs.map((ns, i) => (ns === null || !pins.live[i] ? null : ns / 1000));
  widthsUs.forEach((us, i) => {
    $(`pulse-${i + 1}`).textContent = us === null ? '–' : us.toFixed(2);
  });
  const k = state.kinematics;
  if (!k) {
    return;
  }
  const frame = k.solve(widthsUs);
  frame.armDeg.forEach((deg, i) => {
    $(`arm-${i + 1}`).textContent = Number.isFinite(deg) ? deg.toFixed(3) : '–';
  });
  const solved = frame.status === 'solved';
  state.hasPose ||= solved;
  const pose = [...frame.poseMm, ...frame.poseDeg];
  AXES.forEach((axis, i) => {
    $(`pose-${axis}`).textContent = state.hasPose ? pose[i].toFixed(3) : '–';
  });
  if (solved) {
    jog.showPose(pose);
  }
  const status = $('fk-status');
  status.className = `status ${solved ? 'solved' : 'bad'}`;
  status.textContent = describe(frame);
  status.dataset.status = frame.status;
  scene.update({ ...frame, solved, hasPose: state.hasPose });
}

function describe(frame) {
  const waiting = [...state.asking].map((name) => `\`${name}\``).join(' and ');
  const note = waiting ? ` (asking the board for ${waiting})` : '';
  switch (frame.status) {
    case 'solved':
      return (
        `solved in ${frame.iterations} Newton iteration${frame.iterations === 1 ? '' : 's'}` +
        `; rods close within ${frame.rodErrorMm.toFixed(4)} mm${note}`
      );
    case 'no solution':
      return (
        `no solution: no pose closes all six rods at these arm angles ` +
        `(drawn red at the last pose found)${note}`
      );
    case 'no geometry':
      return state.geometryError
        ? `the board's geometry was refused by the core: ${state.geometryError}`
        : `waiting for the board's geometry listing${note}`;
    case 'no servo settings':
      return state.servosRefused.length > 0
        ? `servo settings refused by the core: servo ${state.servosRefused.join(', ')}`
        : `waiting for the board's config listing${note}`;
    case 'no pulse':
      return 'no pulses on some servo pins';
    default:
      return frame.status;
  }
}

function buildPinRows() {
  const body = document.querySelector('#pins tbody');
  for (let servo = 1; servo <= 6; servo++) {
    const row = document.createElement('tr');
    row.innerHTML = `<th>${servo}</th><td id="pulse-${servo}">–</td><td id="arm-${servo}">–</td>`;
    body.append(row);
  }
}
