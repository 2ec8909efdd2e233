// springy report: the 3D replay of a run (three.js). Bundled by esbuild into one classic script
// (app/CMakeLists.txt) that a page opened from a folder can load. It reads the globals that the
// scene's replay.js sets (app/export_replay.cpp): springyReplayData (the scene) and
// springyReplayMotion (the frames, deflated, in base64), and draws them in every element
// with the class "springy-replay": orbit with the mouse, play, pause and seek with the slider;
// "follow the video" keeps the replay at the video's time.
//
// For tests and scripts, window.springyViewer holds { ready, frame, framesDrawn, error, moving }:
// moving is, per collider or prop that moves, its mesh's position and quaternion at the frame
// shown ([x, y, z, qx, qy, qz, qw]).
import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";

const state = { ready: false, frame: -1, framesDrawn: 0, error: null, moving: [] };
window.springyViewer = state;

function bytesOf(base64) {
  const text = atob(base64);
  const out = new Uint8Array(text.length);
  for (let i = 0; i < text.length; ++i) out[i] = text.charCodeAt(i);
  return out;
}

async function inflate(bytes) {
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  return new Int32Array(await new Response(stream).arrayBuffer());
}

// Every kept frame's positions as floats: frame 0 is quantized positions, each later frame the
// change from the one before.
function decodeMotion(data, deltas) {
  const points = data.bodies.reduce((n, b) => n + b.vertices, 0);
  const frames = data.frames;
  if (deltas.length !== 3 * points * frames) {
    throw new Error(`replay: ${deltas.length} numbers, expected ${3 * points * frames}`);
  }
  const quantum = new Float64Array(3 * points);
  let k = 0;
  for (const b of data.bodies) for (let i = 0; i < 3 * b.vertices; ++i) quantum[k++] = b.quantum;
  const out = new Float32Array(deltas.length);
  const sum = new Int32Array(3 * points);
  for (let f = 0, at = 0; f < frames; ++f) {
    for (let i = 0; i < 3 * points; ++i, ++at) {
      sum[i] += deltas[at];
      out[at] = sum[i] * quantum[i];
    }
  }
  return out;
}

function colorOf(c) {
  return new THREE.Color(c[0], c[1], c[2]);  // linear, as the replay gives it
}

async function mount(root, data, motionBase64) {
  const canvasBox = root.querySelector(".springy-replay-canvas");
  const play = root.querySelector(".springy-replay-play");
  const slider = root.querySelector(".springy-replay-time");
  const label = root.querySelector(".springy-replay-label");
  const follow = root.querySelector(".springy-replay-follow");
  const video = root.dataset.video ? document.getElementById(root.dataset.video) : null;

  const positions = decodeMotion(data, await inflate(bytesOf(motionBase64)));
  const points = data.bodies.reduce((n, b) => n + b.vertices, 0);

  const width = canvasBox.clientWidth || 640;
  const height = Math.round(width * 9 / 16);
  // preserveDrawingBuffer: the drawn frame can be read back (a screenshot, the page's test).
  const renderer = new THREE.WebGLRenderer({ antialias: true, alpha: true, preserveDrawingBuffer: true });
  const css = (c) => `rgb(${c.map((v) => Math.round(255 * Math.min(Math.max(v, 0), 1))).join(",")})`;
  renderer.domElement.style.background = `linear-gradient(${css(data.sky[0])}, ${css(data.sky[1])})`;  // the video's sky
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width, height);
  canvasBox.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x505050, 1.4));
  const sun = new THREE.DirectionalLight(0xffffff, 2.4);  // placed with the camera, below
  scene.add(sun, sun.target);

  const meshes = [];
  const moving = [];
  const box = new THREE.Box3();
  let offset = 0;
  for (const b of data.bodies) {
    const geometry = new THREE.BufferGeometry();
    const attribute = new THREE.BufferAttribute(new Float32Array(3 * b.vertices), 3);
    attribute.setUsage(THREE.DynamicDrawUsage);
    geometry.setAttribute("position", attribute);
    geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(bytesOf(b.triangles).buffer), 1));
    const material = new THREE.MeshStandardMaterial({
      color: colorOf(b.color), roughness: 0.55, metalness: 0.0, flatShading: b.flat,
      transparent: b.alpha < 1, opacity: b.alpha, side: b.open ? THREE.DoubleSide : THREE.FrontSide,
    });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.frustumCulled = false;  // the bodies move; their bounds are not kept up to date
    scene.add(mesh);
    meshes.push({ geometry, attribute, offset: 3 * offset, count: 3 * b.vertices });
    offset += b.vertices;
  }
  for (let i = 0; i < 3 * points; i += 3) box.expandByPoint(new THREE.Vector3(positions[i], positions[i + 1], positions[i + 2]));
  const bodiesBox = box.clone();
  for (const s of data.stills) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(bytesOf(s.xyz).buffer), 3));
    geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(bytesOf(s.triangles).buffer), 1));
    geometry.computeVertexNormals();
    const material = new THREE.MeshStandardMaterial({
      color: colorOf(s.color), roughness: 0.9, side: THREE.DoubleSide, transparent: s.alpha < 1, opacity: s.alpha,
    });
    const mesh = new THREE.Mesh(geometry, material);
    scene.add(mesh);
    if (s.translations) {
      // A collider or prop that moves: its mesh at rest, placed at each frame by its pose.
      const floats = (base64) => new Float32Array(bytesOf(base64).buffer);
      const m = { mesh, translations: floats(s.translations), rotations: s.rotations ? floats(s.rotations) : null };
      if (m.translations.length !== 3 * data.frames || (m.rotations && m.rotations.length !== 4 * data.frames)) {
        throw new Error(`replay: ${s.name} has poses for ${m.translations.length / 3} frames, expected ${data.frames}`);
      }
      moving.push(m);
    }
  }

  // The scene's camera where it gives one, else a view of the bodies from the front and above.
  const centre = bodiesBox.getCenter(new THREE.Vector3());
  const size = Math.max(bodiesBox.getSize(new THREE.Vector3()).length(), 0.5);
  const camera = new THREE.PerspectiveCamera(data.camera.fov || 60, width / height, size / 200, size * 200);
  const target = data.camera.target ? new THREE.Vector3(...data.camera.target) : centre;
  if (data.camera.position) {
    camera.position.set(...data.camera.position);
  } else {
    camera.position.copy(target).add(new THREE.Vector3(0.35, 0.45, 1).normalize().multiplyScalar(1.8 * size));
  }
  // The sun above and to the left of the camera's first view, as the video's light comes.
  sun.position.copy(camera.position).add(new THREE.Vector3(-0.5 * size, 2 * size, 0));
  sun.target.position.copy(target);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(target);
  controls.update();

  let frame = -1;
  function show(f) {
    f = Math.max(0, Math.min(data.frames - 1, f));
    if (f !== frame) {
      frame = f;
      const base = 3 * points * f;
      for (const m of meshes) {
        m.attribute.array.set(positions.subarray(base + m.offset, base + m.offset + m.count));
        m.attribute.needsUpdate = true;
        m.geometry.computeVertexNormals();
      }
      for (const m of moving) {
        m.mesh.position.fromArray(m.translations, 3 * f);
        if (m.rotations) m.mesh.quaternion.fromArray(m.rotations, 4 * f);
      }
      state.moving = moving.map((m) => m.mesh.position.toArray().concat(m.mesh.quaternion.toArray()));
      slider.value = String(f);
      label.textContent = `${(f / data.fps).toFixed(2)} s`;
    }
    renderer.render(scene, camera);
    state.frame = f;
    state.framesDrawn += 1;
  }

  slider.max = String(data.frames - 1);
  let playing = false, startTime = 0, startFrame = 0;
  function tick(now) {
    if (follow && follow.checked && video) {
      show(Math.round(video.currentTime * data.fps));
    } else if (playing) {
      const f = startFrame + Math.floor((now - startTime) / 1000 * data.fps);
      if (f >= data.frames) {
        playing = false;
        play.textContent = "Play";
        show(data.frames - 1);
      } else {
        show(f);
      }
    } else {
      renderer.render(scene, camera);  // orbiting while paused
    }
    requestAnimationFrame(tick);
  }
  play.addEventListener("click", () => {
    playing = !playing;
    if (playing) {
      if (frame >= data.frames - 1) frame = -1, show(0);
      startTime = performance.now();
      startFrame = Math.max(frame, 0);
    }
    play.textContent = playing ? "Pause" : "Play";
  });
  slider.addEventListener("input", () => {
    playing = false;
    play.textContent = "Play";
    show(Number(slider.value));
  });
  show(0);
  requestAnimationFrame(tick);
  state.ready = true;
}

window.addEventListener("DOMContentLoaded", () => {
  const roots = document.querySelectorAll(".springy-replay");
  if (roots.length === 0) return;
  if (!window.springyReplayData || !window.springyReplayMotion) {
    state.error = "the replay's data (replay.js) did not load";
    for (const r of roots) r.querySelector(".springy-replay-label").textContent = state.error;
    return;
  }
  for (const root of roots) {
    mount(root, window.springyReplayData, window.springyReplayMotion).catch((e) => {
      state.error = String(e);
      root.querySelector(".springy-replay-label").textContent = `replay failed: ${e}`;
      console.error(e);
    });
  }
});
