#!/usr/bin/env node
// Time to first pixel and to full detail over a throttled line, in headless
// Chromium with three.js (what `cargo xtask stream-bench` runs).
//
//   node stream-bench.mjs --progressive P.glb --plain F.glb [--name NAME]
//        [--mbit 10] [--latency-ms 50] [--runs 3] [--json OUT.json] [--timeline]
//        [--render task|each]
//
// The local server sends every response after `latency-ms`, at `mbit`
// Mbit/s, responses one after another on the one simulated line. The page
// loads, alternately: F.glb (the plain `--quantize --compress meshopt` full
// mesh) with GLTFLoader + MeshoptDecoder until drawn; P.glb with lodgen's
// loader (coarsest level drawn = first pixel; every level applied and drawn
// = full detail; the page draws once per task, as a render loop would once
// per frame, so levels applied in one go share a draw; `--render each`: a
// draw on every level event). Prints the medians; exit 1 on a failure.

import fs from 'node:fs';
import { bundle, launch, startServer } from './browser.mjs';

const HTML = `<!doctype html>
<html><head><meta charset="utf-8"><title>lodgen stream bench</title>
<style>html,body{margin:0;background:#000}canvas{width:640px;height:480px;display:block}</style></head>
<body><canvas id="c" width="640" height="480"></canvas>
<script type="module" src="/page.js"></script></body></html>
`;

function parseArgs(argv) {
  const o = { mbit: 10, latency: 50, runs: 3, name: 'mesh', render: 'task' };
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i], v = () => argv[++i];
    if (a === '--progressive') o.progressive = v();
    else if (a === '--plain') o.plain = v();
    else if (a === '--name') o.name = v();
    else if (a === '--mbit') o.mbit = Number(v());
    else if (a === '--latency-ms') o.latency = Number(v());
    else if (a === '--runs') o.runs = Number(v());
    else if (a === '--json') o.json = v();
    else if (a === '--timeline') o.timeline = true;
    else if (a === '--render') o.render = v();
    else { console.error(`stream-bench.mjs: unknown argument ${a}`); process.exit(2); }
  }
  if (!o.progressive || !o.plain) { console.error('stream-bench.mjs: needs --progressive P.glb --plain F.glb'); process.exit(2); }
  return o;
}

const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];

async function main() {
  const o = parseArgs(process.argv.slice(2));
  const routes = {
    '/': { type: 'text/html; charset=utf-8', body: Buffer.from(HTML) },
    '/page.js': {
      type: 'text/javascript; charset=utf-8',
      body: await bundle('three-lod-page.js', ['../../crates/lodgen/web/three/index.js', '../../crates/lodgen/web/three/lgpm.js']),
    },
    '/progressive.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.progressive) },
    '/plain.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.plain) },
  };
  const requests = [];
  const server = await startServer(routes, requests, { bitsPerSecond: o.mbit * 1e6, latencyMs: o.latency });
  const errors = [];
  const browser = await launch(errors);
  const runs = { plain: [], first: [], full: [], bytes: [] };
  try {
    const page = browser.page;
    // the page too comes over the slow line (once, before any timing)
    const base = `http://127.0.0.1:${server.address().port}`;
    await page.goto(`${base}/`, { waitUntil: 'load', timeout: 120_000 });
    await page.waitForFunction(() => window.pageReady === true, undefined, { timeout: 120_000 });
    for (let r = 0; r < o.runs; r++) {
      const plain = await page.evaluate((u) => window.runPlain(u), `${base}/plain.glb`);
      requests.length = 0;
      const prog = await page.evaluate(([u, render]) => window.runProgressive(u, { hash: false, render }), [`${base}/progressive.glb`, o.render]);
      const mine = requests.filter((q) => q.path === '/progressive.glb');
      const bytes = mine.length, sent = mine.reduce((n, q) => n + q.sent, 0);
      runs.plain.push(plain.t);
      runs.first.push(prog.firstPixel.t);
      runs.full.push(prog.events[prog.events.length - 1].t);
      runs.bytes.push(bytes);
      console.log(`run ${r + 1}: plain ${plain.t.toFixed(0)} ms (${plain.drawn} triangles); progressive first pixel ` +
        `${prog.firstPixel.t.toFixed(0)} ms (${prog.firstPixel.drawn} triangles), full ${prog.events[prog.events.length - 1].t.toFixed(0)} ms ` +
        `(${prog.events[prog.events.length - 1].drawn} triangles; ${bytes} request(s), ${sent} bytes sent)`);
      if (o.timeline) console.log('  timeline: ' + prog.timeline.map((m) => `${m.what} ${m.t.toFixed(0)} ms (${m.bytes} B)`).join(', ') +
        '; drawn: ' + prog.events.map((e) => `${e.records} records ${e.t.toFixed(0)} ms`).join(', '));
      if (prog.events[prog.events.length - 1].drawn !== plain.drawn) errors.push(`full detail draws ${prog.events[prog.events.length - 1].drawn} triangles, plain ${plain.drawn}`);
    }
  } finally {
    await browser.close();
    server.close();
  }
  const res = {
    name: o.name, mbit: o.mbit, latencyMs: o.latency, runs: o.runs,
    plainBytes: fs.statSync(o.plain).size, progressiveBytes: fs.statSync(o.progressive).size,
    plainMs: median(runs.plain), firstPixelMs: median(runs.first), fullDetailMs: median(runs.full),
  };
  res.firstRatio = res.firstPixelMs / res.plainMs;
  res.fullRatio = res.fullDetailMs / res.plainMs;
  console.log(JSON.stringify(res));
  if (o.json) fs.writeFileSync(o.json, JSON.stringify(res, null, 2));
  const real = errors.filter((e) => !/\(net::ERR_ABORTED\)$/.test(e));
  if (real.length) throw new Error(real.join('; '));
}

main().catch((e) => {
  console.error(`stream-bench.mjs: ${e.stack || e}`);
  process.exit(1);
});
