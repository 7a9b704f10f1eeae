// The page three-lod.mjs and stream-bench.mjs drive (bundled by esbuild):
// three.js from npm, GLTFLoader + MeshoptDecoder, lodgen's three.js loader
// (crates/lodgen/web/three) and three-gltf-extensions' MSFT_lod plugin.
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'meshoptimizer';
import GLTFLodExtension from 'three-gltf-extensions/loaders/MSFT_lod/MSFT_lod.js';
import { loadProgressive, coverageDistance, distanceForCoverage } from '../../crates/lodgen/web/three/index.js';

const t0 = () => performance.now();
const canvas = document.getElementById('c');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
renderer.setSize(canvas.width, canvas.height, false);
const camera = new THREE.PerspectiveCamera(45, canvas.width / canvas.height, 0.001, 1e6);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1b1d22);
scene.add(new THREE.HemisphereLight(0xffffff, 0x334455, 2.5));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(1, 2, 3);
scene.add(sun);

// Bytes handed to WebGL buffers so far (bufferData / bufferSubData on the
// renderer's context): what a draw uploads (the bench).
let uploaded = 0;
{
  const gl = renderer.getContext();
  const bytes = (src, offset, length) => {
    if (typeof src === 'number') return src;
    if (!src || src.byteLength === undefined) return 0;
    const k = src.BYTES_PER_ELEMENT || 1;
    return length ? length * k : src.byteLength - (offset || 0) * k;
  };
  const sub = gl.bufferSubData.bind(gl), data = gl.bufferData.bind(gl);
  gl.bufferSubData = (target, at, src, offset, length) => {
    uploaded += bytes(src, offset, length);
    return offset === undefined ? sub(target, at, src) : sub(target, at, src, offset, length || 0);
  };
  gl.bufferData = (target, src, usage, offset, length) => {
    uploaded += bytes(src, offset, length);
    return offset === undefined ? data(target, src, usage) : data(target, src, usage, offset, length || 0);
  };
}

function frame(object) {
  const sphere = new THREE.Box3().setFromObject(object).getBoundingSphere(new THREE.Sphere());
  camera.position.copy(sphere.center).add(new THREE.Vector3(0.6, 0.35, 1).normalize().multiplyScalar(sphere.radius * 2.6));
  camera.near = sphere.radius / 100;
  camera.far = sphere.radius * 100;
  camera.lookAt(sphere.center);
  camera.updateProjectionMatrix();
  return sphere;
}

// Draw and return what three.js drew, and how long the draw took (ms,
// until its pixels are read back). `pixels: false` (the bench) reads back
// one pixel, enough to wait for the frame, and skips the screenshot's
// variance, a check's cost that a render loop does not pay; 'none' reads
// nothing back (a render loop's frame: the GPU finishes it while the page
// goes on; ms is the time to submit it).
function draw(pixels = true) {
  const start = t0(), u0 = uploaded;
  renderer.render(scene, camera);
  const up = uploaded - u0;
  const gl = renderer.getContext();
  if (pixels === 'none') return { triangles: renderer.info.render.triangles, variance: NaN, uploaded: up, ms: t0() - start };
  if (!pixels) {
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
    return { triangles: renderer.info.render.triangles, variance: NaN, uploaded: up, ms: t0() - start };
  }
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  let s = 0, s2 = 0, image = 0x811c9dc5;
  for (let i = 0; i < px.length; i += 4) {
    image = Math.imul(image ^ (px[i] | (px[i + 1] << 8) | (px[i + 2] << 16)), 0x01000193) >>> 0;
    const l = 0.299 * px[i] + 0.587 * px[i + 1] + 0.114 * px[i + 2];
    s += l;
    s2 += l * l;
  }
  const n = px.length / 4;
  return { triangles: renderer.info.render.triangles, variance: s2 / n - (s / n) ** 2, image, uploaded: up, ms: t0() - start };
}

// FNV-1a 32 over u32 words, little-endian (view.rs index_hash / attribute_hash)
function fnv() {
  let h = 0x811c9dc5;
  return {
    put(v) {
      for (let b = 0; b < 4; b++) {
        h ^= v & 0xff;
        h = Math.imul(h, 0x01000193) >>> 0;
        v >>>= 8;
      }
    },
    value: () => h >>> 0,
  };
}

// The hash of the loader's index state (vertex ids of the drawn triangles).
function indexHash(p) {
  const f = fnv();
  for (let i = 0; i < 3 * p.nt; i++) f.put(p.indices[i]);
  return f.value();
}

// The hash of the drawn vertices' positions as f32 (view.rs position_hash):
// quantized geometry holds grid points q - s, decoded as the stream decodes
// them.
function positionHash(p) {
  const h = p.decoder.header, n = 3 * (h.baseVertices + p.applied), f = fnv(), x = new Float32Array(1), bits = new Uint32Array(x.buffer);
  for (let i = 0; i < n; i++) {
    x[0] = p.quantized ? h.center[i % 3] + (p.vpos[i] / h.scale) * h.half : p.vpos[i];
    f.put(bits[0]);
  }
  return f.value();
}

// With wedges: each drawn corner's group and the values in the geometry's
// attributes (f32 bits), channels in the stream's order; null when a
// channel is not drawn.
function attributeHash(p) {
  const w = p.decoder.header.wedges;
  if (!w) return null;
  const drawn = w.channels.map((c) => p.channels.find((x) => x.c === c));
  if (drawn.some((x) => !x)) return null;
  const bits = drawn.map((x) => new Uint32Array(x.attr.array.buffer));
  // the geometry is indexed: corner c draws vertex index[c] (one per
  // distinct vertex and wedge)
  const index = p.geometry.index.array, f = fnv();
  for (let c = 0; c < 3 * p.nt; c++) {
    const v = index[c];
    f.put(p.decoder.wgroups[p.cw[c]]);
    drawn.forEach((x, i) => { for (let j = 0; j < x.c.components; j++) f.put(bits[i][v * x.c.components + j]); });
  }
  return f.value();
}

// An order-independent hash of the first `nt` triangles of `idx` (each
// triangle's corners in order): the sum of a hash per triangle. The loader
// may draw a level's triangles in another order than its index state
// (order.js): the same triangles, the same sum.
function triangleSetHash(idx, nt) {
  let sum = 0;
  for (let t = 0; t < 3 * nt; t += 3) {
    const f = fnv();
    f.put(idx[t]); f.put(idx[t + 1]); f.put(idx[t + 2]);
    sum = (sum + f.value()) >>> 0;
  }
  return sum;
}

function clear() {
  for (const o of [...scene.children]) if (!o.isLight) scene.remove(o);
}


// Progressive: level events with drawn triangles, hash, pixels; timings.
// `prefetch`: passed to loadProgressive (default `stopAt`; 'none' = not
// passed: the stream beyond its base is fetched when `refine` asks);
// `holdMs` and `worker` too (undefined: the loader's defaults; worker
// false: decoded on the main thread). `then`: a level refined
// to once `stopAt` is shown. `prepareFrame: false`: no frame on the
// loader's "prepare" event in the 'task' mode (the level's upload then
// goes with its own draw).
// `render`: 'each' draws on every level event (what the checks compare);
// 'task' draws once per task as a render loop would per frame (the bench):
// levels the loader applies in one go, their bytes being in already, share
// one draw, and each event's time is the draw that showed it. `pixels`:
// see draw(); with `pixels: false` and 'task', the levels before the last
// are drawn as a render loop draws a frame, not waiting for the GPU (their
// events' time is when the frame was submitted), and the last level's draw
// is waited for (one pixel read back; its events' time). Returns, besides
// the events, `draws` (each draw's start and
// ms), the loader's timeline and main-thread `spent` ms, and the bytes a
// full load needs (`fullBytes`: up to the stream's end).
window.runProgressive = async (url, { stopAt = 0, then, prepareFrame = true, keep = false, hash = true, prefetch = stopAt, render = 'each', pixels = true, holdMs, worker } = {}) => {
  clear();
  const start = t0();
  const loader = new GLTFLoader().setMeshoptDecoder(MeshoptDecoder);
  const p = await loadProgressive(url, { loader, meshoptDecoder: MeshoptDecoder, fetchOptions: { cache: 'no-store' }, prefetch: prefetch === 'none' ? undefined : prefetch, holdMs, worker });
  scene.add(p.gltf.scene);
  frame(p.gltf.scene);
  // first pixel: the coarse level as GLTFLoader parsed it
  const draws = [];
  const timedDraw = () => {
    const at = t0() - start, d = draw(pixels);
    draws.push({ t: at, ms: d.ms, uploaded: d.uploaded });
    return d;
  };
  const first = timedDraw();
  const firstPixel = { drawn: first.triangles, variance: first.variance, t: t0() - start };
  const events = [];
  let waiting = [], drawn = Promise.resolve(), last = null;
  const loop = render === 'task' && pixels === false;
  const show = (ev) => {
    const at = t0() - start, d = draw(loop ? 'none' : pixels);
    draws.push({ t: at, ms: d.ms, uploaded: d.uploaded });
    const t = t0() - start;
    for (const e of ev) Object.assign(e, { drawn: d.triangles, variance: d.variance, image: d.image, t });
    last = ev;
  };
  // the geometry holding the next level's topology before its positions:
  // a render loop draws it in its next frame (the bench: a frame not
  // waited for; 'each': drawn, its image kept to compare with the level's)
  const prepared = [];
  p.addEventListener('prepare', (e) => {
    const ev = { records: e.records, triangles: e.triangles, t: t0() - start };
    prepared.push(ev);
    if (render === 'each') {
      const d = draw(pixels);
      Object.assign(ev, { drawn: d.triangles, image: d.image });
    } else if (prepareFrame) setTimeout(() => { const at = t0() - start, d = draw('none'); draws.push({ t: at, ms: d.ms, uploaded: d.uploaded }); }, 0);
  });
  p.addEventListener('level', (e) => {
    // (the hash below is the check's, not the loader's)
    const ev = { level: e.level, records: e.records, triangles: e.triangles,
      hash: hash ? indexHash(p) : 0, pos: hash ? positionHash(p) : 0, attr: hash ? attributeHash(p) : null,
      attributes: Object.keys(p.geometry.attributes).sort().join(' '),
      // without wedges, the drawn index buffer against the index state
      // (the same triangles; `reordered`: in another array, order.js)
      drawnSet: hash && !p.cw ? triangleSetHash(p.geometry.index.array, p.nt) : 0,
      stateSet: hash && !p.cw ? triangleSetHash(p.indices, p.nt) : 0,
      reordered: p.geometry.index.array !== p.indices };
    events.push(ev);
    if (render === 'each') { show([ev]); return; }
    waiting.push(ev);
    if (waiting.length === 1) drawn = new Promise((r) => setTimeout(() => { const w = waiting; waiting = []; show(w); r(); }, 0));
  });
  await p.refine(stopAt);
  await drawn;
  if (then !== undefined) {
    await p.refine(then);
    await drawn;
  }
  if (loop && last) {
    // the last frame drawn: wait for it
    const gl = renderer.getContext();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
    const t = t0() - start, d = draws[draws.length - 1];
    d.ms = t - d.t;
    for (const e of last) e.t = t;
  }
  if (keep) window.progressive = p;
  return { firstPixel, events, prepared, timeline: p.timeline, received: p.received, coarseTriangles: p.coarseTriangles, quantized: p.quantized,
    draws, spent: p.spent, fullBytes: p.streamStart + p.streamLength, decodedIn: p.inWorker ? 'worker' : 'main', workerError: p.workerError || null,
    // the drawn index's bytes per index, the stream's vertices and corners
    indexBytes: p.geometry.index.array.BYTES_PER_ELEMENT, vertices: p.decoder.header.totalVertices, corners: 3 * p.decoder.header.totalTriangles };
};

// A file whose TEXCOORD_0 is normalized u16 with KHR_texture_transform:
// the finest level streamed against the same level loaded by GLTFLoader
// (its uv as stored u16 values): how many streamed UVs are off every u16
// step by more than 1/100 of one or not among the file's, how many of the
// file's distinct UV pairs are not drawn.
window.uvRangeCheck = async (url) => {
  const r = await window.runProgressive(url, { keep: true, hash: false });
  const p = window.progressive;
  const plain = await new GLTFLoader().setMeshoptDecoder(MeshoptDecoder).loadAsync(url);
  let fileUv = null;
  plain.scene.traverse((o) => { if (o.isMesh && o.visible && !fileUv) fileUv = o.geometry.attributes.uv; });
  const key = (a, b) => a * 65536 + b;
  const file = new Set();
  for (let i = 0; i < fileUv.count; i++) file.add(key(fileUv.array[2 * i], fileUv.array[2 * i + 1]));
  const uv = p.geometry.attributes.uv.array, index = p.geometry.index.array, seen = new Set();
  let unmatched = 0;
  for (let c = 0; c < 3 * p.nt; c++) {
    const v = index[c], a = uv[2 * v] * 65535, b = uv[2 * v + 1] * 65535, qa = Math.round(a), qb = Math.round(b);
    if (Math.abs(a - qa) > 0.01 || Math.abs(b - qb) > 0.01 || !file.has(key(qa, qb))) unmatched++;
    seen.add(key(qa, qb));
  }
  const ch = p.channels.find((x) => x.c.name === 'TEXCOORD_0');
  return { drawn: 3 * p.nt, unmatched, missing: [...file].filter((k) => !seen.has(k)).length, fileValues: file.size,
    transform: ch && ch.remap, events: r.events.length };
};

// The scene as it stands drawn `n` more times, each waited for (one pixel
// read back): the median ms of a frame (the bench, after a load).
window.frameMs = (n = 3) => {
  const ms = [];
  for (let i = 0; i < n; i++) ms.push(draw(false).ms);
  return ms.sort((x, y) => x - y)[Math.floor(n / 2)];
};

// Plain GLTFLoader (+ MeshoptDecoder): time until the full mesh is drawn.
window.runPlain = async (url, { pixels = true } = {}) => {
  clear();
  const start = t0();
  const loader = new GLTFLoader().setMeshoptDecoder(MeshoptDecoder);
  const gltf = await loader.loadAsync(url);
  const loaded = t0() - start;
  scene.add(gltf.scene);
  frame(gltf.scene);
  const d = draw(pixels);
  return { drawn: d.triangles, variance: d.variance, t: t0() - start, loaded, drawMs: d.ms, uploaded: d.uploaded };
};

// The same file without the progressive plugin, through three-gltf-extensions'
// MSFT_lod plugin with the coverageDistance hook: the LOD's levels and, for
// each level switch, the camera distance and the level shown just nearer /
// just farther.
window.runMsftLod = async (url) => {
  clear();
  // the bounding radius of the finest level, for the hook
  const probe = await new GLTFLoader().setMeshoptDecoder(MeshoptDecoder).loadAsync(url);
  const radius = new THREE.Box3().setFromObject(probe.scene).getBoundingSphere(new THREE.Sphere()).radius;
  const loader = new GLTFLoader().setMeshoptDecoder(MeshoptDecoder);
  let coverages = null;
  loader.register((parser) => new GLTFLodExtension(parser, {
    calculateDistance: (level, lowest, cov) => { coverages = cov; return coverageDistance({ camera, radius })(level, lowest, cov); },
  }));
  const gltf = await loader.loadAsync(url);
  scene.add(gltf.scene);
  let lod = null;
  gltf.scene.traverse((o) => { if (o.isLOD) lod = o; });
  if (!lod) return { error: 'no THREE.LOD in the scene' };
  frame(gltf.scene);
  const levels = [];
  for (let i = 0; i < lod.levels.length; i++) {
    lod.levels.forEach((l, j) => { l.object.visible = j === i; });
    let tris = 0;
    lod.levels[i].object.traverse((o) => { if (o.isMesh) tris += o.geometry.index ? o.geometry.index.count / 3 : 0; });
    levels.push({ distance: lod.levels[i].distance, triangles: tris });
  }
  const center = lod.getWorldPosition(new THREE.Vector3());
  const dir = new THREE.Vector3(0, 0, 1);
  const shownAt = (d) => {
    camera.position.copy(center).addScaledVector(dir, d);
    camera.lookAt(center);
    camera.updateMatrixWorld();
    lod.update(camera);
    return lod.getCurrentLevel();
  };
  const switches = [];
  for (let i = 1; i < lod.levels.length; i++) {
    const d = distanceForCoverage(camera, radius, coverages[i - 1]);
    switches.push({ level: i, coverage: coverages[i - 1], distance: d, radius, nearer: shownAt(d * 0.98), farther: shownAt(d * 1.02) });
  }
  frame(gltf.scene);
  lod.update(camera);
  const d = draw();
  return { levels, switches, coverages, drawn: d.triangles, variance: d.variance };
};

// the loader's decoder worker script in the HTTP cache (the bench serves
// it cacheable), as an app's assets come with its page: a load then
// starts the worker without fetching it over the line
fetch(new URL('./worker.js', import.meta.url)).then((r) => r.arrayBuffer()).catch(() => {}).finally(() => { window.pageReady = true; });
