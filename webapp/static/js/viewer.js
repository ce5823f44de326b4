// 3D playback of the four demonstration skeletons (patient, patient adjusted toward the tutor,
// tutor, tutor synchronised to the patient and adjusted), a timeline and linked charts.
//
// Data: `playback.json` (description) and `playback.bin` (float32 world positions laid out as
// [skeleton][frame][joint][xyz]). The browser never parses BVH.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { hiddenParts } from "./skeleton_shape.js";

// Colour per skeleton kind, the same in the toggles, the 3D view and the charts.
export const SKELETON_COLOURS = {
  patient: 0x1f6feb, patient_adjusted: 0x2da44e, tutor: 0x8250df, tutor_adjusted: 0xd4772c,
};
const LEVEL_COLOURS = [0x2da44e, 0x9cc23f, 0xd29922, 0xcf222e]; // level 1 (as tutor) .. 4
const NEUTRAL_JOINT = 0xdadfe5;

export class Playback {
  constructor(root, meta, positions) {
    this.root = root;
    this.meta = meta;
    this.positions = positions;
    this.nFrames = meta.frames;
    this.nJoints = meta.joints;
    this.frame = 0;
    this.playingListeners = [];
    this.playingNow = false;
    // An outside clock (the recording's video, video_sync.js) that playing follows instead of
    // counting frames itself: { frame() -> frame number now, seek(frame) }.
    this.clock = null;
    this.speed = 1;
    this.loop = null; // [start, end] of the repetition being looped
    this.visible = meta.skeletons.map((s, i) => i === 0 || s.key === "tutor_adjusted");
    this.sideBySide = false;
    this.hidden = hiddenParts(meta.parents); // a floor-level placement root is not drawn
    this.listeners = [];
    this.rafCount = 0;
    this.buildScene();
    this.setFrame(0);
    this.lastTime = performance.now();
    this.accumulated = 0;
    requestAnimationFrame((t) => this.tick(t));
  }

  onFrame(listener) { this.listeners.push(listener); }

  // Every start and stop, whoever causes it (buttons, the timeline, the video), is heard here.
  onPlaying(listener) { this.playingListeners.push(listener); }

  get playing() { return this.playingNow; }

  set playing(on) {
    const changed = on !== this.playingNow;
    this.playingNow = on;
    if (changed) this.playingListeners.forEach((listener) => listener(on));
  }

  buildScene() {
    const canvas = this.root.querySelector("canvas");
    // preserveDrawingBuffer lets tests and snapshots read the canvas; pixel ratio capped for speed.
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 1.5));
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xf7f9fb);
    this.camera = new THREE.PerspectiveCamera(45, 1, 1, 10000);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.addEventListener("change", () => { this.dirty = true; });
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 2.2));
    const light = new THREE.DirectionalLight(0xffffff, 1.2);
    light.position.set(200, 400, 300);
    this.scene.add(light);
    this.fitCamera();
    this.skeletons = this.meta.skeletons.map((_, s) => this.buildSkeleton(s));
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  bounds() {
    const p = this.positions;
    const lo = [Infinity, Infinity, Infinity];
    const hi = [-Infinity, -Infinity, -Infinity];
    const stride = Math.max(1, Math.floor(p.length / 3 / 20000)) * 3;
    for (let i = 0; i + 2 < p.length; i += stride) {
      for (let k = 0; k < 3; k++) {
        lo[k] = Math.min(lo[k], p[i + k]);
        hi[k] = Math.max(hi[k], p[i + k]);
      }
    }
    return { lo, hi };
  }

  fitCamera() {
    const { lo, hi } = this.bounds();
    const size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1);
    this.size = size;
    this.floorY = lo[1];
    this.centre = new THREE.Vector3((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2);
    this.camera.position.set(this.centre.x + size * 0.6, this.centre.y + size * 0.35, this.centre.z + size * 1.6);
    this.controls.target.copy(this.centre);
    this.controls.update();
    const grid = new THREE.GridHelper(size * 4, 20, 0xb8c2cc, 0xdfe4ea);
    grid.position.set(this.centre.x, this.floorY, this.centre.z);
    this.scene.add(grid);
  }

  buildSkeleton(s) {
    const group = new THREE.Group();
    const radius = this.size / 90;
    const boneMaterial = new THREE.MeshLambertMaterial({ color: SKELETON_COLOURS[this.meta.skeletons[s].key] ?? 0x888888 });
    const jointMaterial = new THREE.MeshLambertMaterial({ color: 0xffffff });
    const bones = new THREE.InstancedMesh(new THREE.CylinderGeometry(radius, radius, 1, 8, 1, true), boneMaterial, this.nJoints);
    const joints = new THREE.InstancedMesh(new THREE.SphereGeometry(radius * 1.7, 10, 8), jointMaterial, this.nJoints);
    for (let j = 0; j < this.nJoints; j++) joints.setColorAt(j, new THREE.Color(NEUTRAL_JOINT));
    group.add(bones, joints);
    this.scene.add(group);
    return { group, bones, joints };
  }

  resize() {
    const canvas = this.renderer.domElement;
    const width = canvas.clientWidth || 640;
    const height = canvas.clientHeight || 420;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
  }

  offsetFor(s) {
    if (!this.sideBySide) return 0;
    const shown = this.visible.map((v, i) => (v ? i : -1)).filter((i) => i >= 0);
    const slot = shown.indexOf(s);
    return (slot - (shown.length - 1) / 2) * this.size * 0.45;
  }

  poseSkeleton(s) {
    const { bones, joints, group } = this.skeletons[s];
    group.visible = this.visible[s];
    if (!group.visible) return;
    const base = ((s * this.nFrames + this.frame) * this.nJoints) * 3;
    const p = this.positions;
    const dx = this.offsetFor(s);
    const m = new THREE.Matrix4();
    const a = new THREE.Vector3();
    const b = new THREE.Vector3();
    const up = new THREE.Vector3(0, 1, 0);
    const q = new THREE.Quaternion();
    for (let j = 0; j < this.nJoints; j++) {
      a.set(p[base + 3 * j] + dx, p[base + 3 * j + 1], p[base + 3 * j + 2]);
      joints.setMatrixAt(j, this.hidden.joints.has(j) ? m.makeScale(0, 0, 0) : m.makeTranslation(a.x, a.y, a.z));
      const parent = this.meta.parents[j];
      if (parent < 0 || this.hidden.bones.has(j)) { bones.setMatrixAt(j, m.makeScale(0, 0, 0)); continue; }
      b.set(p[base + 3 * parent] + dx, p[base + 3 * parent + 1], p[base + 3 * parent + 2]);
      const length = a.distanceTo(b);
      q.setFromUnitVectors(up, b.clone().sub(a).normalize());
      m.compose(a.clone().add(b).multiplyScalar(0.5), q, new THREE.Vector3(1, Math.max(length, 1e-6), 1));
      bones.setMatrixAt(j, m);
    }
    bones.instanceMatrix.needsUpdate = true;
    joints.instanceMatrix.needsUpdate = true;
  }

  colourJoints(levelsByJoint) {
    const { joints } = this.skeletons[0];
    const colour = new THREE.Color();
    this.meta.names.forEach((name, j) => {
      const level = levelsByJoint ? levelsByJoint[name] : undefined;
      colour.setHex(level ? LEVEL_COLOURS[Math.min(level, 4) - 1] : NEUTRAL_JOINT);
      joints.setColorAt(j, colour);
    });
    joints.instanceColor.needsUpdate = true;
  }

  setFrame(frame) {
    this.frame = Math.max(0, Math.min(this.nFrames - 1, Math.round(frame)));
    this.skeletons.forEach((_, s) => this.poseSkeleton(s));
    this.colourJoints(levelsAt(this.meta, this.frame));
    this.dirty = true; // drawn once in the next animation frame, however often the frame is set
    this.listeners.forEach((listener) => listener(this.frame));
  }

  tick(time) {
    this.rafCount += 1;
    const elapsed = (time - this.lastTime) / 1000;
    this.lastTime = time;
    if (this.playing && this.clock) {
      this.followClock();
    } else if (this.playing) {
      this.accumulated += elapsed * this.meta.fps * this.speed;
      const step = Math.floor(this.accumulated);
      if (step > 0) {
        this.accumulated -= step;
        this.setFrame(this.nextFrame(step));
      }
    }
    this.controls.update();
    if (this.dirty) {
      this.dirty = false;
      this.renderer.render(this.scene, this.camera);
    }
    requestAnimationFrame((t) => this.tick(t));
  }

  followClock() {
    const frame = Math.round(this.clock.frame());
    if (this.loop && (frame > this.loop[1] || frame < this.loop[0])) {
      this.clock.seek(this.loop[0]);
      this.setFrame(this.loop[0]);
    } else if (frame !== this.frame) {
      this.setFrame(frame);
    }
  }

  nextFrame(step) {
    let next = this.frame + step;
    if (this.loop) {
      const [start, end] = this.loop;
      if (next > end || next < start) next = start;
    } else if (next >= this.nFrames) {
      next = 0;
    }
    return next;
  }
}

// The assessment levels of the key pose nearest before this frame (joint name -> level).
export function levelsAt(meta, frame) {
  let found = null;
  for (const item of meta.assessment || []) {
    if (item.frame <= frame) found = item; else break;
  }
  return found ? found.levels : null;
}
