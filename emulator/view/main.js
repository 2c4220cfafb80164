// The live view's page: connects to the runner's event stream (emulator/src/view-server/view-server.js),
// runs every pin update through the project's kinematics (kinematics.js, WebAssembly) and shows
// the result: the 3D picture (scene.js), the readout (pulses in us, arm angles in deg, the pose
// in mm and deg) and the board's serial output (terminal.js). When the emulator stops it says
// so and keeps the last picture.

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
};

const scene = new PlatformScene($('stage'));
const terminal = new PageTerminal({
  container: $('terminal'),
  form: $('send'),
  input: $('line'),
  note: $('send-note'),
});
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
  events.addEventListener('hello', () => {
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
  events.addEventListener('geometry', (event) => {
    state.geometry = JSON.parse(event.data);
    state.asking.delete('geometry');
    applyGeometry();
  });
  events.addEventListener('config', (event) => {
    state.config = JSON.parse(event.data);
    state.asking.delete('config');
    applyConfig();
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

function showStopped() {
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
  $('emulated-time').textContent = `${(pins.nanos / 1e9).toFixed(1)} s`;
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
