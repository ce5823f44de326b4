// The reachable workspace of each hand as a small 3D view: the covered patch of the unit sphere
// around each shoulder (arm lengths; X anterior, Y superior, Z lateral), drawn beside a wireframe
// front hemisphere. The hulls come from the page (json_script "workspace-data"); three.js from the
// page's import map (templates/recordings/viewer.html).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const COLOURS = { left: 0x2da44e, right: 0x1f6feb };

function hullMesh(hull) {
  // Left hand mirrored to the body's left (Z lateral is stored away from the body on both sides),
  // and each shoulder placed half a unit from the centre so both patches are visible.
  const sign = hull.side === "left" ? -1 : 1;
  const geometry = new THREE.BufferGeometry();
  const xyz = hull.vertices.flatMap(([x, y, z]) => [x, y, sign * z + sign * 0.6]);
  geometry.setAttribute("position", new THREE.Float32BufferAttribute(xyz, 3));
  geometry.setIndex(hull.faces.flat());
  geometry.computeVertexNormals();
  const material = new THREE.MeshLambertMaterial({ color: COLOURS[hull.side] ?? 0x888888, side: THREE.DoubleSide, transparent: true, opacity: 0.85 });
  return new THREE.Mesh(geometry, material);
}

function hemisphere(offset) {
  const geometry = new THREE.SphereGeometry(1, 16, 8, -Math.PI / 2, Math.PI); // x >= 0: in front
  const mesh = new THREE.LineSegments(new THREE.WireframeGeometry(geometry), new THREE.LineBasicMaterial({ color: 0xc4cbd4 }));
  mesh.position.z = offset;
  return mesh;
}

function draw() {
  const canvas = document.getElementById("workspace-canvas");
  const data = document.getElementById("workspace-data");
  if (!canvas || !data) return;
  const hulls = JSON.parse(data.textContent);
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf7f9fb);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 2.0));
  hulls.forEach((hull) => { scene.add(hullMesh(hull)); scene.add(hemisphere(hull.side === "left" ? -0.6 : 0.6)); });
  const camera = new THREE.PerspectiveCamera(40, 1, 0.1, 100);
  camera.position.set(4.5, 1.2, 0);  // in front of the patient, looking back at them
  const controls = new OrbitControls(camera, canvas);
  const render = () => {
    const { clientWidth: w, clientHeight: h } = canvas;
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
    renderer.render(scene, camera);
  };
  controls.addEventListener("change", render);
  new ResizeObserver(render).observe(canvas);
  render();
  canvas.dataset.ready = "1";
}

draw();
