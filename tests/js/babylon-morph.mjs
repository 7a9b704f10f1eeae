#!/usr/bin/env node
// Babylon.js animates a morph weight of a lodgen output in headless Chromium.
//
//   node babylon-morph.mjs [--timeout SEC] FILE.glb ANIMATION NODE
//
// Loads FILE.glb with Babylon's glTF loader (MSFT_lod, every level) in
// Chromium (browser.mjs), then plays the animation group ANIMATION and
// samples the morph target influences at ten times over its keyframes.
// Passes when the mesh of glTF node NODE (its finest level, the one shown
// once loading is done) has the file's morph targets (count, names from
// extras.targetNames), and its influences follow the file's weights channel
// of NODE (linear interpolation of its keyframes, within 1e-3) at every
// sample, with no page error, console error or failed request.
// Exit 0 on success, 1 on failure, 2 on bad usage.

import fs from 'node:fs';
import path from 'node:path';
import { bundle, checker, launch, startServer } from './browser.mjs';

const HTML = `<!doctype html>
<html><head><meta charset="utf-8"><title>lodgen morph check</title>
<style>html,body{margin:0}canvas{width:320px;height:240px;display:block}</style></head>
<body><canvas id="c" width="320" height="240"></canvas>
<script type="module" src="/page.js"></script></body></html>
`;

function usage(msg) {
  console.error(`babylon-morph.mjs: ${msg}\nusage: node babylon-morph.mjs [--timeout SEC] FILE.glb ANIMATION NODE`);
  process.exit(2);
}

function parseArgs(argv) {
  const o = { timeoutSec: 90, args: [] };
  for (let i = 0; i < argv.length; i++) {
    if (argv[i] === '--timeout') o.timeoutSec = Number(argv[++i]);
    else if (argv[i].startsWith('-')) usage(`unknown option ${argv[i]}`);
    else o.args.push(argv[i]);
  }
  if (o.args.length !== 3 || !(o.timeoutSec > 0)) usage('expected FILE.glb ANIMATION NODE');
  [o.glb, o.animation] = o.args;
  o.node = Number(o.args[2]);
  return o;
}

function glbParts(b) {
  if (b.length < 28 || b.readUInt32LE(0) !== 0x46546c67) throw new Error('not a GLB');
  const jsonLen = b.readUInt32LE(12);
  const gltf = JSON.parse(b.subarray(20, 20 + jsonLen).toString('utf8'));
  const at = 20 + jsonLen;
  const bin = at + 8 <= b.length ? b.subarray(at + 8, at + 8 + b.readUInt32LE(at)) : Buffer.alloc(0);
  return { gltf, bin };
}

// A float accessor's values (tightly packed, no sparse).
function floats({ gltf, bin }, a) {
  const acc = gltf.accessors[a];
  const view = gltf.bufferViews[acc.bufferView];
  const n = acc.count * { SCALAR: 1, VEC2: 2, VEC3: 3, VEC4: 4 }[acc.type];
  const off = (view.byteOffset ?? 0) + (acc.byteOffset ?? 0);
  if (acc.componentType !== 5126) throw new Error(`accessor ${a}: not float`);
  return Array.from({ length: n }, (_, i) => bin.readFloatLE(off + 4 * i));
}

// The weights the file's channel gives node `node` at time t (LINEAR).
function expectedWeights(glb, animation, node, targets) {
  const anim = glb.gltf.animations?.find((a) => a.name === animation);
  const ch = anim?.channels.find((c) => c.target.node === node && c.target.path === 'weights');
  if (!ch) return null;
  const s = anim.samplers[ch.sampler];
  const keys = floats(glb, s.input);
  const values = floats(glb, s.output);
  return (t) => {
    let k = 0;
    while (k + 1 < keys.length && keys[k + 1] <= t) k++;
    const f = k + 1 < keys.length ? (t - keys[k]) / (keys[k + 1] - keys[k]) : 0;
    return Array.from({ length: targets }, (_, j) => {
      const a = values[k * targets + j];
      const b = k + 1 < keys.length ? values[(k + 1) * targets + j] : a;
      return a + (b - a) * Math.min(1, Math.max(0, f));
    });
  };
}

async function main() {
  const o = parseArgs(process.argv.slice(2));
  const bytes = fs.readFileSync(o.glb);
  const glb = glbParts(bytes);
  const { check, failures } = checker();
  const node = glb.gltf.nodes[o.node];
  const mesh = glb.gltf.meshes[node?.mesh];
  if (!mesh) usage(`node ${o.node} draws no mesh`);
  const targets = mesh.primitives[0].targets?.length ?? 0;
  const names = mesh.extras?.targetNames ?? [];
  const weightsAt = expectedWeights(glb, o.animation, o.node, targets);
  check(targets > 0, `node ${o.node} (mesh '${mesh.name}') has ${targets} morph target(s) in the file`);
  check(weightsAt !== null, `animation '${o.animation}' has a weights channel of node ${o.node}`);
  const anim = glb.gltf.animations.find((a) => a.name === o.animation);
  const end = Math.max(...anim.samplers.map((s) => glb.gltf.accessors[s.input].max[0]));
  const times = Array.from({ length: 10 }, (_, i) => (end * i) / 9);

  const errors = [];
  const server = await startServer({
    '/': { type: 'text/html; charset=utf-8', body: Buffer.from(HTML) },
    '/page.js': { type: 'text/javascript; charset=utf-8', body: await bundle('babylon-morph-page.js') },
    '/model.glb': { type: 'model/gltf-binary', body: bytes },
  });
  const base = `http://127.0.0.1:${server.address().port}`;
  const browser = await launch(errors, { viewport: { width: 320, height: 240 } });
  let timer;
  try {
    const { page } = browser;
    const run = (async () => {
      await page.goto(`${base}/`, { waitUntil: 'load' });
      await page.waitForFunction(() => window.morphPageReady === true, undefined, { timeout: 30_000 });
      return page.evaluate(([url, a, t]) => window.runMorphTest(url, a, t), [`${base}/model.glb`, o.animation, times]);
    })();
    const timeout = new Promise((_, reject) => {
      timer = setTimeout(() => reject(new Error(`timed out after ${o.timeoutSec} s`)), o.timeoutSec * 1000);
    });
    const r = await Promise.race([run, timeout]);
    console.log(`babylon-morph: Babylon.js ${r.babylonVersion} on ${r.engine}; animation groups [${r.groups.join(', ')}]`);
    for (const m of r.loaded) console.log(`  loaded '${m.name}'${m.enabled ? '' : ' (disabled)'}: ${m.vertices} vertices, targets [${m.targets.join(', ')}]`);
    // the finest level's meshes: Babylon names a node's mesh after the node
    const shown = r.loaded.filter((m) => m.enabled && m.name.startsWith(node.name ?? `node${o.node}`));
    check(shown.length > 0, `Babylon shows node ${o.node} ('${node.name}') with morph targets`);
    for (const m of shown) {
      check(m.targets.length === targets, `'${m.name}': ${m.targets.length} morph target(s), the file has ${targets}`);
      if (names.length) check(m.targets.join() === names.join(), `'${m.name}': target names [${m.targets}] = extras.targetNames [${names}]`);
    }
    check(r.samples.length === times.length, `${r.samples.length} samples of animation '${o.animation}'`);
    let moved = false;
    for (const s of r.samples) {
      const want = weightsAt ? weightsAt(s.t) : [];
      for (const m of s.meshes.filter((x) => shown.some((y) => y.name === x.name))) {
        const ok = m.influences.length === want.length && m.influences.every((v, j) => Math.abs(v - want[j]) < 1e-3);
        check(ok, `t=${s.t.toFixed(3)} s '${m.name}': influences [${m.influences.map((v) => v.toFixed(3))}], file [${want.map((v) => v.toFixed(3))}]`);
        if (m.influences.some((v) => v > 0.1)) moved = true;
      }
    }
    check(moved, 'the animation moved the morph weight');
  } finally {
    clearTimeout(timer);
    await browser.close();
    server.close();
  }
  for (const e of errors) check(false, e);
  if (failures.length) {
    console.log(`babylon-morph: ${path.basename(o.glb)}: FAILED (${failures.length} problem(s))`);
    process.exit(1);
  }
  console.log(`babylon-morph: ${path.basename(o.glb)}: ok`);
  process.exit(0);
}

main().catch((e) => {
  console.log(`FAIL: ${e?.stack ?? e}`);
  process.exit(1);
});
