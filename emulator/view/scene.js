// The 3D picture (three.js): base, servos, arms at the measured angles, rods, platform at the
// pose the forward kinematics found, leg numbers. Base frame as in the documented geometry: origin
// at the centre of the servo shafts' plane, z up, lengths in mm; the platform frame is placed by
// the pose (its origin as the kinematics gives it: (x, y, h0 + z), moved by c - R c about a
// pivot c; R = Rz(yaw) Ry(pitch) Rx(roll), eq. 1). It draws only what it is given
// (kinematics.js computes every point) and renders on demand: after new data or a camera move.

import {
  AmbientLight,
  BoxGeometry,
  Color,
  CylinderGeometry,
  DirectionalLight,
  ExtrudeGeometry,
  GridHelper,
  Group,
  HemisphereLight,
  Mesh,
  MeshBasicMaterial,
  MeshStandardMaterial,
  PerspectiveCamera,
  Scene,
  Shape,
  SphereGeometry,
  Vector3,
  WebGLRenderer,
} from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { CSS2DObject, CSS2DRenderer } from 'three/addons/renderers/CSS2DRenderer.js';

/** The platform plate's top, flat (unlit) so it is one colour on screen: #f28c28. */
export const PLATFORM_COLOUR = 0xf28c28;
const PLATFORM_SIDE_COLOUR = 0xb8621a;
/** The platform and rods when the pins' arm angles have no pose (no FK solution). */
export const NO_SOLUTION_COLOUR = 0xe53935;
const ROD_COLOUR = 0xcfd8dc;
const PLATE_THICKNESS_MM = 4;

const Y_AXIS = new Vector3(0, 1, 0);

/** Camera presets: azimuth from +x towards +y and elevation, degrees; distance in sizes. */
export const CAMERAS = {
  iso: { azimuth: -50, elevation: 24, distance: 4.4 },
  side: { azimuth: 0, elevation: 10, distance: 4.0 },
  front: { azimuth: -90, elevation: 10, distance: 4.0 },
  top: { azimuth: -90, elevation: 89.5, distance: 4.4 },
};

export class PlatformScene {
  constructor(container) {
    this.container = container;
    this.renderer = new WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    container.appendChild(this.renderer.domElement);
    this.labels = new CSS2DRenderer();
    this.labels.domElement.className = 'labels';
    container.appendChild(this.labels.domElement);

    this.scene = new Scene();
    this.scene.background = new Color(0x1b1f24);
    this.scene.add(new HemisphereLight(0xffffff, 0x404850, 1.6));
    this.scene.add(new AmbientLight(0xffffff, 0.3));
    const sun = new DirectionalLight(0xffffff, 1.8);
    sun.position.set(200, -300, 500);
    this.scene.add(sun);

    this.camera = new PerspectiveCamera(40, 1, 1, 5000);
    this.camera.up.set(0, 0, 1);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.requestRender());

    this.model = null;
    this.size = 100;
    this.homeHeightMm = 100;
    this.renderPending = false;
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const { clientWidth: width, clientHeight: height } = this.container;
    if (width === 0 || height === 0) {
      return;
    }
    this.renderer.setSize(width, height);
    this.labels.setSize(width, height);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  requestRender() {
    if (this.renderPending) {
      return;
    }
    this.renderPending = true;
    requestAnimationFrame(() => {
      this.renderPending = false;
      this.renderer.render(this.scene, this.camera);
      this.labels.render(this.scene, this.camera);
    });
  }

  /** Points the camera from a preset direction (CAMERAS) at the middle of the platform. */
  setCamera(name) {
    const preset = CAMERAS[name] ?? CAMERAS.iso;
    const target = new Vector3(0, 0, this.homeHeightMm * 0.4);
    const az = (preset.azimuth * Math.PI) / 180;
    const el = (preset.elevation * Math.PI) / 180;
    const d = preset.distance * this.size;
    this.camera.position.set(
      target.x + d * Math.cos(el) * Math.cos(az),
      target.y + d * Math.cos(el) * Math.sin(az),
      target.z + d * Math.sin(el),
    );
    this.controls.target.copy(target);
    this.controls.update();
    this.requestRender();
  }

  /**
   * Builds the model of a geometry: `base` b_i and `platform` p_i (mm), `betaDeg` per leg, arm
   * length a, home height h0 (mm).
   */
  setGeometry({ base, platform, betaDeg, armMm, homeHeightMm }) {
    if (this.model) {
      this.scene.remove(this.model.group);
      this.model.group.traverse((o) => {
        o.geometry?.dispose();
        o.element?.remove();
      });
    }
    const group = new Group();
    const radius = Math.max(...base.map(([x, y]) => Math.hypot(x, y)));
    this.size = radius + armMm;
    this.homeHeightMm = homeHeightMm;

    const grid = new GridHelper(this.size * 4, 16, 0x3c444d, 0x2a3038);
    grid.rotation.x = Math.PI / 2; // into the xy plane
    grid.position.z = -30;
    group.add(grid);

    const baseDisc = new Mesh(
      new CylinderGeometry(radius + 22, radius + 22, 6, 64),
      new MeshStandardMaterial({ color: 0x59616b, roughness: 0.8 }),
    );
    baseDisc.rotation.x = Math.PI / 2;
    baseDisc.position.z = -27;
    group.add(baseDisc);

    const servoMaterial = new MeshStandardMaterial({ color: 0x29465c, roughness: 0.6 });
    const hubMaterial = new MeshStandardMaterial({ color: 0xdfe4ea, roughness: 0.4 });
    const armMaterial = new MeshStandardMaterial({
      color: 0xe9ecef,
      metalness: 0.3,
      roughness: 0.35,
    });
    const rodMaterial = new MeshStandardMaterial({
      color: ROD_COLOUR,
      metalness: 0.5,
      roughness: 0.3,
    });
    const jointMaterial = new MeshStandardMaterial({ color: 0x90a4ae, roughness: 0.4 });
    const arms = [];
    const rods = [];
    const tipJoints = [];
    const platformJoints = [];
    base.forEach(([x, y, z], i) => {
      const beta = (betaDeg[i] * Math.PI) / 180;
      // The servo body below its shaft, its long side along the arm's plane.
      const body = new Mesh(new BoxGeometry(24, 12, 24), servoMaterial);
      body.position.set(x, y, z - 12);
      body.rotation.z = beta;
      group.add(body);
      const hub = new Mesh(new CylinderGeometry(5, 5, 14, 24), hubMaterial);
      hub.position.set(x, y, z);
      hub.rotation.z = beta; // the shaft: square to the arm's plane
      group.add(hub);

      arms.push(this.stick(group, 2.5, armMaterial));
      rods.push(this.stick(group, 1.3, rodMaterial));
      tipJoints.push(this.ball(group, 3, jointMaterial));
      platformJoints.push(this.ball(group, 3, jointMaterial));

      const outward = new Vector3(x, y, 0).normalize().multiplyScalar(22);
      group.add(this.text(String(i + 1), 'leg-label', [x + outward.x, y + outward.y, z + 6]));
    });

    // The plate: a hexagon through the six platform joints (sorted by angle), a little larger,
    // from the joints' plane up; drawn in the platform frame and placed by the pose.
    const corners = platform
      .map(([x, y]) => [x * 1.15, y * 1.15])
      .sort((a, b) => Math.atan2(a[1], a[0]) - Math.atan2(b[1], b[0]));
    const shape = new Shape();
    corners.forEach(([x, y], k) => (k === 0 ? shape.moveTo(x, y) : shape.lineTo(x, y)));
    shape.closePath();
    const plateTop = new MeshBasicMaterial({ color: PLATFORM_COLOUR });
    const plateSide = new MeshBasicMaterial({ color: PLATFORM_SIDE_COLOUR });
    const plate = new Mesh(
      new ExtrudeGeometry(shape, { depth: PLATE_THICKNESS_MM, bevelEnabled: false }),
      [plateTop, plateSide],
    );
    const platformFrame = new Group();
    platformFrame.rotation.order = 'ZYX'; // R = Rz(yaw) Ry(pitch) Rx(roll): eq. 1
    platformFrame.add(plate);
    // The platform's +x axis, so yaw shows.
    const pointer = new Mesh(
      new BoxGeometry(radius * 0.35, 3, 1),
      new MeshBasicMaterial({ color: 0x1b1f24 }),
    );
    pointer.position.set(radius * 0.25, 0, PLATE_THICKNESS_MM + 0.6);
    platformFrame.add(pointer);
    platformFrame.add(this.text('+x', 'axis-label', [radius * 0.5, 0, PLATE_THICKNESS_MM + 2]));
    group.add(platformFrame);

    this.model = {
      group,
      arms,
      rods,
      tipJoints,
      platformJoints,
      platformFrame,
      plateTop,
      plateSide,
      rodMaterial,
      base: base.map((b) => new Vector3(...b)),
    };
    this.scene.add(group);
    this.requestRender();
  }

  /** A text label (HTML, always facing the camera) at `position` (mm). */
  text(content, className, position) {
    const element = document.createElement('div');
    element.className = className;
    element.textContent = content;
    const label = new CSS2DObject(element);
    label.position.set(...position);
    return label;
  }

  /** A cylinder of `radius` to be stretched between two points by `place`. */
  stick(group, radius, material) {
    const mesh = new Mesh(new CylinderGeometry(radius, radius, 1, 16), material);
    group.add(mesh);
    return mesh;
  }

  ball(group, radius, material) {
    const mesh = new Mesh(new SphereGeometry(radius, 16, 12), material);
    group.add(mesh);
    return mesh;
  }

  place(stick, from, to) {
    const direction = new Vector3().subVectors(to, from);
    const length = direction.length();
    stick.visible = length > 1e-6;
    if (!stick.visible) {
      return;
    }
    stick.position.addVectors(from, to).multiplyScalar(0.5);
    stick.scale.set(1, length, 1);
    stick.quaternion.setFromUnitVectors(Y_AXIS, direction.divideScalar(length));
  }

  /**
   * Draws one solve (kinematics.js): arms to their tips (always: they come from the pulses),
   * rods to the platform joints and the plate at the pose found; in red, at the last pose found,
   * when there is no solution. `solved` false and no pose yet hides the platform.
   */
  update({ tips, joints, originMm, poseDeg, solved, hasPose }) {
    const m = this.model;
    if (!m) {
      return;
    }
    const tipPoints = tips.map((t) => new Vector3(...t));
    const jointPoints = joints.map((q) => new Vector3(...q));
    const armsKnown = tipPoints.every((t) => Number.isFinite(t.x + t.y + t.z));
    m.base.forEach((b, i) => {
      m.arms[i].visible = armsKnown;
      m.tipJoints[i].visible = armsKnown;
      if (armsKnown) {
        this.place(m.arms[i], b, tipPoints[i]);
        m.tipJoints[i].position.copy(tipPoints[i]);
      }
      m.rods[i].visible = armsKnown && hasPose;
      m.platformJoints[i].visible = hasPose;
      if (armsKnown && hasPose) {
        this.place(m.rods[i], tipPoints[i], jointPoints[i]);
      }
      m.platformJoints[i].position.copy(jointPoints[i]);
    });
    m.platformFrame.visible = hasPose;
    const [roll, pitch, yaw] = poseDeg.map((d) => (d * Math.PI) / 180);
    m.platformFrame.position.set(...originMm);
    m.platformFrame.rotation.set(roll, pitch, yaw, 'ZYX');
    m.plateTop.color.set(solved ? PLATFORM_COLOUR : NO_SOLUTION_COLOUR);
    m.plateSide.color.set(solved ? PLATFORM_SIDE_COLOUR : NO_SOLUTION_COLOUR);
    m.rodMaterial.color.set(solved ? ROD_COLOUR : NO_SOLUTION_COLOUR);
    this.requestRender();
  }
}
