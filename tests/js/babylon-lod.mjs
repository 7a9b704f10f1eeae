#!/usr/bin/env node
// A real client for lodgen's MSFT_lod output: Babylon.js in headless Chromium.
//
//   node babylon-lod.mjs [--timeout SEC] [--null-engine] FILE.glb REPORT.json
//
// Serves FILE.glb and a page bundling @babylonjs/core + @babylonjs/loaders
// (from node_modules, bundled in memory by esbuild) on 127.0.0.1 (random free
// port), opens the page in Debian's /usr/bin/chromium (override with env
// LODGEN_CHROMIUM) through playwright-core, loads the file with Babylon's glTF
// loader (MSFT_lod enabled, with HTTP range requests so that each level's data
// is fetched only after the coarser level is shown; WebGL on a real canvas
// unless --null-engine) and records, at each "node LODs loaded"
// event of the MSFT_lod extension, which glTF node of every LOD chain Babylon
// holds and its triangle count.
//
// REPORT.json: {"meshes":[{"name":"...","levels":[{"triangles":N,...}, ...finest first]}]}
// Passes when every reported mesh is one MSFT_lod chain that Babylon loads
// coarse-to-fine, one level per event, with exactly the reported triangle
// counts. Fails (exit 1) on any mismatch, page error, console error, failed
// request, or after the timeout (default 90 s). Exit 2 on bad usage.

import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { chromium } from 'playwright-core';
import { CHROMIUM, CHROMIUM_ARGS, bundle, startServer } from './browser.mjs';

function usage(msg) {
  console.error(
    `babylon-lod.mjs: ${msg}\n` +
      'usage: node babylon-lod.mjs [--timeout SEC] [--null-engine] FILE.glb REPORT.json',
  );
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { timeoutSec: 90, nullEngine: false, files: [] };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--timeout') {
      opts.timeoutSec = Number(argv[++i]);
      if (!(opts.timeoutSec > 0)) usage('--timeout needs a positive number of seconds');
    } else if (a === '--null-engine') opts.nullEngine = true;
    else if (a.startsWith('-')) usage(`unknown option ${a}`);
    else opts.files.push(a);
  }
  if (opts.files.length !== 2) usage('expected FILE.glb and REPORT.json');
  [opts.glb, opts.report] = opts.files;
  return opts;
}

function readGlbJson(file) {
  const b = fs.readFileSync(file);
  if (b.length < 20 || b.readUInt32LE(0) !== 0x46546c67) throw new Error(`${file}: not a GLB (bad magic)`);
  if (b.readUInt32LE(4) !== 2) throw new Error(`${file}: GLB version ${b.readUInt32LE(4)}, expected 2`);
  const len = b.readUInt32LE(12);
  if (b.readUInt32LE(16) !== 0x4e4f534a) throw new Error(`${file}: first GLB chunk is not JSON`);
  return { bytes: b, gltf: JSON.parse(b.subarray(20, 20 + len).toString('utf8')) };
}

// LOD chains of the file, checked against what issue 3 asks of the writer.
function lodChains(gltf) {
  const nodes = gltf.nodes ?? [];
  const used = gltf.extensionsUsed ?? [];
  const required = gltf.extensionsRequired ?? [];
  if (!used.includes('MSFT_lod')) failures.push('MSFT_lod is not listed in extensionsUsed');
  if (required.includes('MSFT_lod')) failures.push('MSFT_lod is listed in extensionsRequired (must be in extensionsUsed only)');
  const inScene = new Set();
  for (const s of gltf.scenes ?? []) {
    const stack = [...(s.nodes ?? [])];
    while (stack.length) {
      const n = stack.pop();
      if (inScene.has(n)) continue;
      inScene.add(n);
      stack.push(...(nodes[n]?.children ?? []));
    }
  }
  const chains = [];
  nodes.forEach((node, i) => {
    const ext = node.extensions?.MSFT_lod;
    if (!ext) return;
    const finestFirst = [i, ...(ext.ids ?? [])];
    const name = node.name ?? `node${i}`;
    const meshName = node.mesh !== undefined ? gltf.meshes?.[node.mesh]?.name : undefined;
    for (const id of finestFirst.slice(1)) {
      if (!nodes[id]) failures.push(`${name}: MSFT_lod id ${id} is not a node`);
      else if (inScene.has(id)) failures.push(`${name}: coarser level node ${id} is listed in a scene (clients would draw it too)`);
    }
    if (!inScene.has(i)) failures.push(`${name}: finest level node ${i} is not in any scene`);
    const cov = node.extras?.MSFT_screencoverage;
    const levels = finestFirst.length;
    if (!Array.isArray(cov)) failures.push(`${name}: extras.MSFT_screencoverage missing`);
    else if (cov.length !== levels && cov.length !== levels + 1)
      failures.push(`${name}: MSFT_screencoverage has ${cov.length} values for ${levels} levels`);
    chains.push({ key: String(i), name, meshName, nodes: [...finestFirst].reverse() });
  });
  return chains;
}

function readReport(file) {
  const r = JSON.parse(fs.readFileSync(file, 'utf8'));
  if (!Array.isArray(r?.meshes) || r.meshes.length === 0) throw new Error(`${file}: no "meshes" array`);
  for (const m of r.meshes) {
    if (!Array.isArray(m.levels) || m.levels.length === 0) throw new Error(`${file}: mesh ${m.name}: no "levels"`);
    for (const l of m.levels)
      if (!Number.isInteger(l.triangles)) throw new Error(`${file}: mesh ${m.name}: level without integer "triangles"`);
  }
  return r;
}

// Report mesh -> chain: by name (finest node's name or its mesh's name), else by order.
function pairUp(report, chains) {
  const byName = report.meshes.map((m) => chains.filter((c) => c.name === m.name || c.meshName === m.name));
  const taken = new Set();
  const named = byName.every((cs) => cs.length === 1 && !taken.has(cs[0].key) && taken.add(cs[0].key));
  if (named && report.meshes.length === chains.length) {
    return { how: 'by name', pairs: report.meshes.map((m, i) => [m, byName[i][0]]) };
  }
  if (report.meshes.length !== chains.length) {
    failures.push(`report lists ${report.meshes.length} meshes, the file has ${chains.length} MSFT_lod chains`);
    return { how: 'none', pairs: [] };
  }
  return { how: 'by order (names did not match one-to-one)', pairs: report.meshes.map((m, i) => [m, chains[i]]) };
}

// The page bundle (cached in node_modules/.cache/lodgen, see browser.mjs).
const bundlePage = () => bundle('babylon-lod-page.js');

const HTML = `<!doctype html>
<html><head><meta charset="utf-8"><title>lodgen MSFT_lod check</title>
<style>html,body{margin:0}canvas{width:640px;height:480px;display:block}</style></head>
<body><canvas id="c" width="640" height="480"></canvas>
<script type="module" src="/page.js"></script></body></html>
`;

async function runBrowser(opts, glbBytes, chains, pageErrors) {
  const t0 = Date.now();
  const requests = [];
  const routes = {
    '/': { type: 'text/html; charset=utf-8', body: Buffer.from(HTML) },
    '/page.js': { type: 'text/javascript; charset=utf-8', body: await bundlePage() },
    '/model.glb': { type: 'model/gltf-binary', body: glbBytes },
  };
  const server = await startServer(routes, requests);
  const base = `http://127.0.0.1:${server.address().port}`;
  console.log(`babylon-lod: page bundled (${routes['/page.js'].body.length} bytes) and served at ${base}/ in ${Date.now() - t0} ms`);
  const userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), 'lodgen-chromium-'));
  let context;
  try {
    const t1 = Date.now();
    context = await chromium.launchPersistentContext(userDataDir, {
      executablePath: CHROMIUM,
      headless: true,
      args: CHROMIUM_ARGS,
      timeout: 60_000,
    });
    const page = context.pages()[0] ?? (await context.newPage());
    console.log(`babylon-lod: ${CHROMIUM} ${context.browser()?.version() ?? ''} started in ${Date.now() - t1} ms`.trim());
    page.on('pageerror', (e) => pageErrors.push(`page error: ${e.message}`));
    page.on('console', (msg) => {
      const text = msg.text();
      if (msg.type() === 'warning' && text.includes('GL Driver Message')) return; // SwiftShader performance chatter
      console.log(`  [console.${msg.type()}] ${text}`);
      if (msg.type() === 'error') pageErrors.push(`console error: ${text}`);
    });
    page.on('requestfailed', (req) => pageErrors.push(`request failed: ${req.url()} (${req.failure()?.errorText})`));
    page.on('response', (res) => {
      if (res.status() >= 400) pageErrors.push(`HTTP ${res.status()} for ${res.url()}`);
    });
    await page.goto(`${base}/`, { waitUntil: 'load' });
    await page.waitForFunction(() => window.lodPageReady === true, undefined, { timeout: 30_000 });
    const t2 = Date.now();
    const result = await page.evaluate(
      ([url, c, o]) => window.runLodTest(url, c, o),
      [`${base}/model.glb`, chains.map((c) => ({ key: c.key, nodes: c.nodes })), { nullEngine: opts.nullEngine }],
    );
    result.loadMs = Date.now() - t2;
    result.requests = requests.filter((r) => r.path === '/model.glb');
    return result;
  } finally {
    await context?.close().catch(() => {});
    server.close();
    fs.rmSync(userDataDir, { recursive: true, force: true });
  }
}

function compare(pairs, result) {
  const seq = result.events.map((e) => e.indexLOD);
  const expectedSeq = seq.map((_, i) => i);
  if (seq.join() !== expectedSeq.join()) failures.push(`MSFT_lod node-LOD events came as [${seq}], expected [${expectedSeq}]`);
  for (const [m, c] of pairs) {
    const n = m.levels.length;
    const want = [...m.levels].reverse().map((l) => l.triangles); // coarse first
    const problems = [];
    if (c.nodes.length !== n) problems.push(`file has ${c.nodes.length} levels, report ${n}`);
    // 1. The order in which Babylon shows this chain's levels, with their
    // triangles: the enabled node of the chain at each node-LOD event, in
    // event order. (onEnabledStateChanged alone misses the coarsest level
    // when it is enabled before the observer is attached: a small file
    // loads that fast.)
    const en = [...result.events]
      .sort((a, b) => a.indexLOD - b.indexLOD)
      .flatMap((ev) => (ev.chains[c.key] ?? []).filter((l) => l.enabled).slice(0, 1));
    const enNodes = en.map((e) => e.node);
    if (enNodes.join() !== c.nodes.join())
      problems.push(`Babylon enabled nodes [${enNodes}], expected coarse-to-fine [${c.nodes}]`);
    en.forEach((e, k) => {
      if (k < n && e.triangles !== want[k]) problems.push(`level ${k} (coarse=0): Babylon ${e.triangles} triangles, report ${want[k]}`);
    });
    // 2. With range requests each level is shown before the next one's data is
    // fetched: at the k-th node-LOD event the k-th level is the one enabled.
    for (let k = 0; k < c.nodes.length; k++) {
      const ev = result.events.find((e) => e.indexLOD === k);
      if (!ev) {
        problems.push(`no node-LOD event ${k}`);
        continue;
      }
      const live = ev.chains[c.key] ?? [];
      const on = live.filter((l) => l.enabled).map((l) => l.node);
      if (on.length !== 1 || on[0] !== c.nodes[k])
        problems.push(`at node-LOD event ${k} the enabled nodes of this chain are [${on}], expected [${c.nodes[k]}]`);
      const stale = live.filter((l) => c.nodes.indexOf(l.node) < k).map((l) => l.node);
      if (stale.length) problems.push(`at node-LOD event ${k} coarser level nodes [${stale}] are still loaded`);
    }
    const status = problems.length ? 'MISMATCH' : 'ok';
    console.log(
      `  ${m.name} (chain of node ${c.key} '${c.name}'): Babylon coarse-to-fine [${en.map((e) => e.triangles).join(', ')}], ` +
        `report [${want.join(', ')}]: ${status}`,
    );
    for (const p of problems) failures.push(`${m.name}: ${p}`);
  }
}

const failures = [];
const pageErrors = [];

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  const { bytes, gltf } = readGlbJson(opts.glb);
  const report = readReport(opts.report);
  const chains = lodChains(gltf);
  const { how, pairs } = pairUp(report, chains);
  console.log(`babylon-lod: ${opts.glb}: ${chains.length} MSFT_lod chain(s), report ${opts.report} paired ${how}`);
  if (!fs.existsSync(CHROMIUM)) throw new Error(`${CHROMIUM} not found (install Debian's chromium or set LODGEN_CHROMIUM)`);

  let timer;
  const timeout = new Promise((_, reject) => {
    timer = setTimeout(() => reject(new Error(`timed out after ${opts.timeoutSec} s`)), opts.timeoutSec * 1000);
  });
  const result = await Promise.race([runBrowser(opts, bytes, chains, pageErrors), timeout]);
  clearTimeout(timer);

  console.log(
    `babylon-lod: Babylon.js ${result.babylonVersion} on ${result.engine}, MSFT_lod extension ${result.lodExtension ? 'enabled' : 'NOT enabled'}, ` +
      `loaded in ${result.loadMs} ms`,
  );
  if (!result.lodExtension) failures.push("Babylon's MSFT_lod extension was not enabled for this file");
  for (const r of result.requests) console.log(`  GET /model.glb ${r.range ?? '(whole file)'} -> ${r.status}`);
  for (const e of result.events) {
    const parts = Object.entries(e.chains).map(
      ([k, live]) => `node ${k}: ` + (live.map((l) => `#${l.node} '${l.name}' ${l.triangles} tris ${l.vertices} verts${l.enabled ? '' : ' (disabled)'}`).join(' + ') || 'nothing'),
    );
    console.log(`  event indexLOD=${e.indexLOD} at +${e.tMs} ms: ${parts.join('; ')}`);
  }
  console.log(`  after loading, one frame drew ${result.finalDrawnTriangles} triangles`);
  for (const [key, en] of Object.entries(result.enabled)) {
    console.log(`  node ${key} levels as enabled: ` + en.map((e) => `#${e.node} '${e.name}' ${e.triangles} tris ${e.vertices} verts at +${e.tMs} ms`).join(', '));
  }
  compare(pairs, result);
  failures.push(...pageErrors);
  if (failures.length) {
    for (const f of failures) console.log(`FAIL: ${f}`);
    console.log(`babylon-lod: ${path.basename(opts.glb)}: FAILED (${failures.length} problem(s))`);
    process.exit(1);
  }
  console.log(`babylon-lod: ${path.basename(opts.glb)}: ok`);
  process.exit(0);
}

main().catch((e) => {
  for (const f of [...failures, ...pageErrors]) console.log(`FAIL: ${f}`);
  console.log(`FAIL: ${e?.message ?? e}`);
  console.log('babylon-lod: FAILED');
  process.exit(1);
});
