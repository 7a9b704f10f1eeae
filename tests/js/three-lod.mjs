#!/usr/bin/env node
// lodgen's three.js loader (crates/lodgen/web/three) in headless Chromium.
//
//   node three-lod.mjs --lodgen BIN FILE.glb [--attributes ATTR.glb] [--uv-range UV.glb] [--float F.glb] [--out DIR]      (or env LODGEN_BIN)
//
// FILE.glb is a `lodgen --progressive` output. Expectations come from
// `BIN view --print-levels FILE.glb` (each level's records, triangles,
// index hash and position hash, from lodgen's own decoder). Checks, with three.js, GLTFLoader and MeshoptDecoder from npm:
// loadProgressive shows the coarsest level first, then one "level" event per
// MSFT_lod level, coarse to fine, each drawing exactly the level's triangles
// (renderer.info) with the level's index hash and its vertices at the
// positions Rust decodes (f32 bits); the first pixel is the
// coarsest level; the drawn index is 16-bit when the mesh has at most 65,535
// vertices (as glTF files store it); the GLB is read from its start in one request (JSON,
// coarsest level, stream); stopping at a middle level without prefetch reads
// the stream's base on that request, the rest up to the level by one range
// request, and fewer stream bytes; over a throttled line (50 Mbit/s) that
// brings the whole stream well within `holdMs: 1000`, every level (the
// base's included) is applied in one go: the page, drawing once per task,
// shows them all in one draw; screenshots of the coarsest and finest level are
// not blank (DIR/three-*.png, default target/test-out). The same file without
// the progressive plugin, through three-gltf-extensions' MSFT_lod plugin with
// the coverageDistance hook, is a THREE.LOD with every level (its triangle
// counts), switching level where the file's MSFT_screencoverage says.
// ATTR.glb (a stream with wedges, e.g. spot.obj's UVs and normals): every
// level draws the level's triangles, index and position hashes and corner attribute hash
// (each corner's group and drawn attribute values, `attributeHash`), with
// the streamed UVs and normals as three.js attributes.
// UV.glb (glTF input with a textured material whose UVs leave [0, 1],
// written with --quantize: TEXCOORD_0 normalized u16 plus
// KHR_texture_transform): the finest streamed level's UVs are the file's
// finest level's, in the file's space (each within 1/100 of a u16 step of
// one of its values, and every one of its values drawn).
// F.glb (written without --quantize: f32 positions, which the loader
// computes from the records' grid points): every level draws the level's
// triangles, index hash and position hash.
// Before the browser, each file's stream decoded in node (lgpm.js) pushed 1,
// 7, 1000 and 8192 bytes at a time decodes as pushed whole (records, grid
// points, wedges, their values, the topology callbacks).
// Exit 0 on success, 1 on failure, 2 on bad usage.

import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { HERE, MIN_VARIANCE, bundle, checker, launch, startServer } from './browser.mjs';

const HTML = `<!doctype html>
<html><head><meta charset="utf-8"><title>lodgen three.js check</title>
<style>html,body{margin:0;background:#000}canvas{width:640px;height:480px;display:block}</style></head>
<body><canvas id="c" width="640" height="480"></canvas>
<script type="module" src="/page.js"></script></body></html>
`;

function usage(msg) {
  console.error(`three-lod.mjs: ${msg}\nusage: node three-lod.mjs --lodgen BIN FILE.glb [--out DIR]`);
  process.exit(2);
}

function parseArgs(argv) {
  const o = { out: path.resolve(HERE, '../../target/test-out'), lodgen: process.env.LODGEN_BIN, files: [] };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--lodgen') o.lodgen = argv[++i];
    else if (a === '--out') o.out = path.resolve(argv[++i]);
    else if (a === '--attributes') o.attributes = argv[++i];
    else if (a === '--uv-range') o.uvRange = argv[++i];
    else if (a === '--float') o.float = argv[++i];
    else if (a.startsWith('-')) usage(`unknown option ${a}`);
    else o.files.push(a);
  }
  if (!o.lodgen || o.files.length !== 1) usage('expected --lodgen BIN FILE.glb');
  return o;
}

const { check, failures } = checker();
const LOADER = ['index.js', 'lgpm.js', 'order.js', 'remote.js', 'worker.js'].map((f) => `../../crates/lodgen/web/three/${f}`);

// Level events of two loads of one file (the worker's and the main
// thread's decoder): the same records, triangles drawn and hashes.
function sameLevels(a, b) {
  return a.length === b.length && a.every((e, i) => e.records === b[i].records && e.drawn === b[i].drawn && e.hash === b[i].hash &&
    e.pos === b[i].pos && e.attr === b[i].attr && e.drawnSet === b[i].drawnSet);
}
const levelList = (r) => r.events.map((e) => `${e.records}: ${e.drawn} triangles, hash ${e.hash}`).join('; ');

// The stream of a progressive GLB decoded in node by lgpm.js's
// StreamDecoder, its bytes pushed `size` at a time (0: at once): a
// signature of everything the loader reads (records, grid points, wedges
// and their values) and the onTopology calls (k: records), so that every
// split of the bytes can be checked to decode the same (a chunk's
// topology, its wedge ids, its wedges' values and its positions are each
// decoded as soon as their columns are in).
function decodeSplit(StreamDecoder, mo, glbPath, size) {
  const b = fs.readFileSync(glbPath), jl = b.readUInt32LE(12), json = JSON.parse(b.subarray(20, 20 + jl).toString());
  let ext = null;
  for (const m of json.meshes) for (const p of m.primitives) if (p.extensions && p.extensions.LODGEN_progressive) ext = p.extensions.LODGEN_progressive;
  const bv = json.bufferViews[ext.bufferView], at = 28 + jl + (bv.byteOffset || 0);
  const s = new Uint8Array(b.buffer, b.byteOffset + at, bv.byteLength);
  const d = new StreamDecoder(mo), topology = [];
  d.floats = false;
  d.onTopology = (k) => topology.push(`${k}:${d.wfaces0 ? d.nw : ''}`);
  const step = size || s.length;
  for (let i = 0; i < s.length; i += step) d.push(s.subarray(i, Math.min(s.length, i + step)));
  const mix = (arr) => { let x = 0; for (let i = 0; i < arr.length; i++) x = (Math.imul(x, 31) + (arr[i] >>> 0)) | 0; return x >>> 0; };
  const w = d.wfaces0 ? [d.wfaces0, d.wafter.a.subarray(0, d.wafter.n), new Uint32Array(d.wvals.buffer), d.wgroups] : [];
  return `${d.count} records; ${[d.faces0, d.corners.a.subarray(0, d.corners.n), d.v1, d.fStart, d.cStart, d.q1, d.q0, ...w].map(mix).join(',')}; topology ${topology.join(' ')}`;
}

async function main() {
  const o = parseArgs(process.argv.slice(2));
  const expect = JSON.parse(execFileSync(o.lodgen, ['view', '--print-levels', o.files[0]], { encoding: 'utf8' }));
  const levels = expect.levels; // finest first
  fs.mkdirSync(o.out, { recursive: true });
  {
    // the decoder in node: any split of the bytes decodes the same
    const { StreamDecoder } = await import('../../crates/lodgen/web/three/lgpm.js');
    const { MeshoptDecoder } = await import('meshoptimizer');
    await MeshoptDecoder.ready;
    for (const f of [o.files[0], o.attributes, o.float].filter(Boolean)) {
      const whole = decodeSplit(StreamDecoder, MeshoptDecoder, f, 0);
      for (const size of [1, 7, 1000, 8192]) {
        const got = decodeSplit(StreamDecoder, MeshoptDecoder, f, size);
        check(got === whole, `${path.basename(f)}: the stream pushed ${size} byte(s) at a time decodes as pushed whole (${got === whole ? whole : `${got}, whole: ${whole}`})`);
      }
    }
  }
  const requests = [];
  const routes = {
    '/': { type: 'text/html; charset=utf-8', body: Buffer.from(HTML) },
    '/page.js': {
      type: 'text/javascript; charset=utf-8',
      body: await bundle('three-lod-page.js', LOADER),
    },
    // the loader's decoder worker, where the page's bundle looks for it
    // (new URL("./worker.js", import.meta.url))
    '/worker.js': { type: 'text/javascript; charset=utf-8', body: await bundle('../../crates/lodgen/web/three/worker.js', LOADER), cache: true },
    // a worker that dies at once: the loader decodes on the main thread
    '/broken-worker.js': { type: 'text/javascript; charset=utf-8', body: Buffer.from('throw new Error("no decoder here");\n') },
    '/model.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.files[0]) },
    '/slow.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.files[0]), throttle: { bitsPerSecond: 50e6, latencyMs: 5 } },
    // (a line on which the finest level's positions come well after its topology)
    '/slower.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.files[0]), throttle: { bitsPerSecond: 2.5e6, latencyMs: 5 } },
    ...(o.attributes ? { '/attributes.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.attributes) } } : {}),
    ...(o.uvRange ? { '/uvrange.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.uvRange) } } : {}),
    ...(o.float ? { '/float.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.float) } } : {}),
  };
  const server = await startServer(routes, requests);
  const base = `http://127.0.0.1:${server.address().port}`;
  const errors = [];
  const browser = await launch(errors);
  try {
    const page = browser.page;
    await page.goto(`${base}/`, { waitUntil: 'load' });
    await page.waitForFunction(() => window.pageReady === true, undefined, { timeout: 30_000 });

    // progressive, to the finest level
    requests.length = 0;
    const r = await page.evaluate(() => window.runProgressive('/model.glb'));
    check(r.decodedIn === 'worker', `decoded in a Web Worker (${r.decodedIn}${r.workerError ? ': ' + r.workerError : ''})`);
    const glbRequests = requests.filter((q) => q.path === '/model.glb');
    check(glbRequests.length >= 1 && glbRequests.every((q) => q.status === 206),
      `GLB fetched in ${glbRequests.length} range request(s) (${glbRequests.map((q) => q.range).join(', ')})`);
    check(r.received === expect.streamBytes, `the loader read the whole stream (${r.received} of ${expect.streamBytes} bytes)`);
    const want = [...levels].reverse(); // coarse → fine
    check(r.events.length === want.length,
      `${r.events.length} level events (expected ${want.length}: one per MSFT_lod level)`);
    r.events.forEach((e, i) => {
      const lv = want[i];
      if (!lv) return;
      check(e.records === lv.records && e.drawn === lv.triangles && e.hash === lv.indexHash && e.pos === lv.positionHash,
        `level ${e.level}: ${e.records} records, drew ${e.drawn} triangles, hash ${e.hash}, position hash ${e.pos} ` +
          `(expected ${lv.records}, ${lv.triangles}, ${lv.indexHash}, ${lv.positionHash}) at ${e.t.toFixed(0)} ms`);
    });
    check(r.events.every((e) => e.drawnSet === e.stateSet) && r.events[r.events.length - 1].reordered,
      `every level draws its index state's triangles (order-independent hashes ${r.events.map((e) => `${e.drawnSet}/${e.stateSet}`).join(', ')}), ` +
        `the finest in the split tree's draw order (${r.events.map((e) => e.reordered).join(', ')})`);
    check(r.indexBytes === (r.vertices <= 65535 ? 2 : 4),
      `the drawn index is ${8 * r.indexBytes}-bit for ${r.vertices} vertices (16-bit below 65,535, as glTF stores such meshes)`);
    check(r.firstPixel.drawn === want[0].triangles && r.firstPixel.variance > MIN_VARIANCE,
      `first pixel: the coarsest level drawn (${r.firstPixel.drawn} triangles, variance ${r.firstPixel.variance.toFixed(1)}) at ${r.firstPixel.t.toFixed(0)} ms`);
    check(r.coarseTriangles === want[0].triangles,
      `the coarsest level's own primitive has the stream base's ${want[0].triangles} triangles (${r.coarseTriangles})`);
    for (const [i, e] of [[0, r.events[0]], [r.events.length - 1, r.events[r.events.length - 1]]]) {
      const file = path.join(o.out, `three-progressive-${i === 0 ? 'coarsest' : 'finest'}.png`);
      check(e.variance > MIN_VARIANCE, `progressive ${i === 0 ? 'coarsest' : 'finest'} level not blank: variance ${e.variance.toFixed(1)}`);
      if (i !== 0) await page.screenshot({ path: file });
    }

    // the synchronous path (worker: false) and a worker that fails to
    // start (its bytes decoded on the main thread): every level as the
    // worker's, drawn in the same order
    {
      const m = await page.evaluate(() => window.runProgressive('/model.glb', { worker: false }));
      check(m.decodedIn === 'main' && sameLevels(m.events, r.events),
        `worker: false decodes on the main thread (${m.decodedIn}) and draws what the worker's load drew: ${levelList(m)}`);
      const f = await page.evaluate(() => window.runProgressive('/model.glb', { worker: '/broken-worker.js' }));
      check(f.decodedIn === 'main' && !!f.workerError && sameLevels(f.events, r.events),
        `a worker that fails to start: decoded on the main thread (${f.decodedIn}, ${f.workerError}), the same levels: ${levelList(f)}`);
      const g = await page.evaluate(() => window.runProgressive('/slow.glb', { worker: false, hash: false }));
      const h = await page.evaluate(() => window.runProgressive('/slow.glb', { hash: false }));
      check(h.decodedIn === 'worker' && g.events.map((e) => e.drawn).join() === h.events.map((e) => e.drawn).join(),
        `over a 50 Mbit/s line, worker and main thread draw the same triangle counts (${h.events.map((e) => e.drawn).join(', ')}; ${g.events.map((e) => e.drawn).join(', ')})`);
    }

    // levels the line brings within holdMs share one frame
    {
      const h = await page.evaluate(() => window.runProgressive('/slow.glb', { hash: false, render: 'task', holdMs: 1000 }));
      const draws = new Set(h.events.map((e) => e.t)).size;
      check(h.events.length === levels.length && draws === 1 && h.events[h.events.length - 1].drawn === levels[0].triangles,
        `holdMs 1000 on a 50 Mbit/s line: ${h.events.length} level events in ${draws} draw(s) (expected ${levels.length} in 1), ` +
          `finest ${h.events[h.events.length - 1].drawn} triangles`);
    }

    // stopped at level 1, then refined to the finest over a 2.5 Mbit/s line:
    // the topology of the level refine stops at goes into the geometry
    // before its positions ("prepare": here level 1, then the finest),
    // drawn as the level before it, pixel for pixel
    if (levels.length >= 3) {
      // (a worker whose topology comes in the last eighth of the level's
      // bytes, the machine being busy, prepares nothing: a second try)
      let q = null;
      for (let attempt = 0; attempt < 2 && !(q && q.prepared.some((x) => x.records === levels[0].records)); attempt++) {
        q = await page.evaluate(() => window.runProgressive('/slower.glb', { stopAt: 1, prefetch: 'none', then: 0 }));
      }
      const fin = q.events[q.events.length - 1], pr = q.prepared;
      const coarser = (k) => { const j = levels.findIndex((l) => l.records === k); return j >= 0 && j + 1 < levels.length ? levels[j + 1].records : -1; };
      check(pr.length >= 1 && pr[pr.length - 1].records === levels[0].records && pr[pr.length - 1].triangles === levels[0].triangles &&
        pr.every((x) => levels.some((l) => l.records === x.records && l.triangles === x.triangles)),
        `prepare: ${pr.length} event(s), the last for the finest level's ${levels[0].records} records and ${levels[0].triangles} ` +
          `triangles (${pr.map((x) => `${x.records} records, ${x.triangles} triangles`).join('; ')})`);
      pr.forEach((x) => {
        const before = q.events.find((e) => e.records === coarser(x.records));
        check(before && x.drawn === x.triangles && x.image === before.image,
          `prepare for ${x.records} records: its ${x.drawn} triangles drawn as the level before it (image ${x.image}, ` +
            `${before ? `${before.records} records' ${before.image}` : 'no level before it'})`);
      });
      check(fin.records === levels[0].records && fin.hash === levels[0].indexHash && fin.pos === levels[0].positionHash && fin.drawnSet === fin.stateSet,
        `prepare: the finest level then drawn with its hashes (${fin.hash}, ${fin.pos}; expected ${levels[0].indexHash}, ${levels[0].positionHash})`);
    }

    // stop at a middle level, the stream beyond its base asked for only by
    // refine (no prefetch: a range request): no chunk beyond it is fetched
    if (levels.length >= 3) {
      const mid = Math.floor((levels.length - 1) / 2);
      requests.length = 0;
      const s = await page.evaluate((m) => window.runProgressive('/model.glb', { stopAt: m, prefetch: 'none' }), mid);
      const last = s.events[s.events.length - 1];
      const stopBytes = s.received, fullBytes = r.received;
      check(last.drawnSet === last.stateSet && last.reordered && s.events.slice(0, -1).every((e) => !e.reordered && e.drawnSet === e.stateSet),
        `stopped at level ${mid}: drawn in the split tree's order, its index state's triangles (${last.drawnSet}/${last.stateSet}); the levels before it in the state's order`);
      check(last.records === levels[mid].records && last.drawn === levels[mid].triangles,
        `stopped at level ${mid}: ${last.records} records, ${last.drawn} triangles drawn (` +
          `${stopBytes} stream bytes read; to the finest ${fullBytes})`);
      check(stopBytes < fullBytes, 'stopping early fetches fewer bytes of the stream');
      const ranged = requests.filter((q) => q.path === '/model.glb');
      check(ranged.length === 2 && ranged[1].status === 206 && /^bytes=\d+-\d+$/.test(ranged[1].range || ''),
        `without prefetch, refine fetches the rest of the stream by a range request (${ranged.map((q) => q.range).join(', ')})`);
    }

    // a stream with attributes: drawn with them, exactly
    if (o.attributes) {
      const want = JSON.parse(execFileSync(o.lodgen, ['view', '--print-levels', o.attributes], { encoding: 'utf8' })).levels;
      const a = await page.evaluate(() => window.runProgressive('/attributes.glb'));
      check(a.events.length === want.length, `attributes: ${a.events.length} level events (expected ${want.length})`);
      const am = await page.evaluate(() => window.runProgressive('/attributes.glb', { worker: false }));
      check(a.decodedIn === 'worker' && am.decodedIn === 'main' && sameLevels(am.events, a.events),
        `attributes: the worker's levels (${a.decodedIn}) are the main thread's (${am.decodedIn}): ${levelList(am)}`);
      a.events.forEach((e, i) => {
        const lv = want[want.length - 1 - i];
        if (!lv) return;
        check(e.records === lv.records && e.drawn === lv.triangles && e.hash === lv.indexHash && e.attr === lv.attributeHash && e.pos === lv.positionHash,
          `attributes: level ${e.level}: ${e.records} records, drew ${e.drawn} triangles, hash ${e.hash}, corner attribute hash ` +
            `${e.attr}, position hash ${e.pos} (expected ${lv.records}, ${lv.triangles}, ${lv.indexHash}, ${lv.attributeHash}, ` +
            `${lv.positionHash}); attributes ${e.attributes}`);
      });
      check(a.indexBytes === (a.corners <= 65535 ? 2 : 4),
        `attributes: the drawn index (one vertex per (vertex, wedge) pair, at most one per corner) is ${8 * a.indexBytes}-bit for ${a.corners} corners`);
      const last = a.events[a.events.length - 1];
      check(/\bnormal\b/.test(last.attributes) && /\buv\b/.test(last.attributes) && last.variance > MIN_VARIANCE,
        `attributes: the finest level draws streamed normals and UVs (${last.attributes}), not blank (variance ${last.variance.toFixed(1)})`);
      await page.screenshot({ path: path.join(o.out, 'three-progressive-attributes.png') });
    }

    // f32 positions: each level's vertices where Rust decodes them
    if (o.float) {
      const want = JSON.parse(execFileSync(o.lodgen, ['view', '--print-levels', o.float], { encoding: 'utf8' })).levels;
      const f = await page.evaluate(() => window.runProgressive('/float.glb'));
      check(f.events.length === want.length && !f.quantized, `float: ${f.events.length} level events (expected ${want.length}), f32 positions`);
      f.events.forEach((e, i) => {
        const lv = want[want.length - 1 - i];
        if (!lv) return;
        check(e.records === lv.records && e.drawn === lv.triangles && e.hash === lv.indexHash && e.pos === lv.positionHash,
          `float: level ${e.level}: ${e.records} records, drew ${e.drawn} triangles, hash ${e.hash}, position hash ${e.pos} ` +
            `(expected ${lv.records}, ${lv.triangles}, ${lv.indexHash}, ${lv.positionHash})`);
      });
    }

    // UVs quantized over their range with KHR_texture_transform: the
    // stream's UVs land in the file's space
    if (o.uvRange) {
      const u = await page.evaluate(() => window.uvRangeCheck('/uvrange.glb'));
      check(u.transform && u.unmatched === 0 && u.missing === 0 && u.drawn > 0,
        `uv range: ${u.drawn} streamed UVs, ${u.unmatched} off the file's u16 values, ${u.missing} of the file's ${u.fileValues} ` +
          `values not drawn; texture transform ${JSON.stringify(u.transform)}`);
    }

    // without the plugin: three-gltf-extensions' MSFT_lod, coverage hook
    const m = await page.evaluate(() => window.runMsftLod('/model.glb'));
    check(!m.error, `MSFT_lod plugin builds a THREE.LOD${m.error ? ': ' + m.error : ''}`);
    if (!m.error) {
      const tris = m.levels.map((l) => l.triangles);
      check(JSON.stringify(tris) === JSON.stringify(levels.map((l) => l.triangles)),
        `THREE.LOD levels have [${tris.join(', ')}] triangles (expected [${levels.map((l) => l.triangles).join(', ')}])`);
      for (const s of m.switches) {
        check(s.nearer === s.level - 1 && s.farther === s.level,
          `level ${s.level} takes over at coverage ${s.coverage.toExponential(3)} = ${(s.distance / s.radius).toFixed(1)} radii ` +
            `(2 % nearer shows ${s.nearer}, 2 % farther ${s.farther})`);
      }
      await page.screenshot({ path: path.join(o.out, 'three-msft-lod.png') });
      check(m.variance > MIN_VARIANCE && m.drawn > 0, `MSFT_lod scene not blank: ${m.drawn} triangles, variance ${m.variance.toFixed(1)}`);
    }
    // Chromium now and then reports a whole-file GET of GLTFLoader as
    // net::ERR_ABORTED although the load completed (every check above
    // passed on its data): not counted, but printed
    const aborted = errors.filter((e) => / {2}\(net::ERR_ABORTED\)$/.test(e));
    if (aborted.length) console.log(`note: ${aborted.join('; ')}`);
    const real = errors.filter((e) => !aborted.includes(e));
    check(real.length === 0, `no page errors${real.length ? ': ' + real.join('; ') : ''}`);
  } finally {
    await browser.close();
    server.close();
  }
}

main().then(
  () => {
    if (failures.length) {
      console.error(`three-lod.mjs: ${failures.length} check(s) failed`);
      process.exit(1);
    }
  },
  (e) => {
    console.error(`three-lod.mjs: ${e.stack || e}`);
    process.exit(1);
  },
);
