#!/usr/bin/env node
// Time to first pixel and to full detail over a throttled line, in headless
// Chromium with three.js (what `cargo xtask stream-bench` runs).
//
//   node stream-bench.mjs --progressive P.glb --plain F.glb [--name NAME]
//        [--mbit 10] [--latency-ms 50] [--runs 3] [--json OUT.json] [--timeline]
//        [--render task|each] [--hold-ms MS] [--no-prepare-frame]
//        [--decode worker|main|both] [--cold]
//
// The local server sends every response after `latency-ms`, at `mbit`
// Mbit/s, responses one after another on the one simulated line. The page
// loads, alternately: F.glb (the plain `--quantize --compress meshopt` full
// mesh) with GLTFLoader + MeshoptDecoder until drawn; P.glb with lodgen's
// loader (coarsest level drawn = first pixel; every level applied and drawn
// = full detail; the page draws once per task, as a render loop would once
// per frame, so levels applied in one go share a draw, and draws a frame, not
// waited for, on the loader's "prepare" event (`--no-prepare-frame`: not);
// `--decode`: where the loader decodes the stream, in its Web Worker
// (default, the loader's default) or on the page's main thread (its
// `worker: false`); `both`: each run loads the progressive file both ways
// after its plain load, in turn (worker first in odd runs, main in even
// ones), and the table has a line for each: two loaders compared under the
// same load. `--cold`: the page loaded anew before each progressive load
// (a page's one load: the decoder's JIT cold, in the worker or not; else
// the main thread's decoder and the loader's idle worker are warm from the
// runs before). `--render each`: a
// draw on every level event; `--hold-ms`: the loader's holdMs, default its
// own). A draw is timed until one pixel is read
// back (the frame done), without the checks' screenshot. Prints each run,
// then the medians with their spread (min – max over the runs) and the
// median of the runs' own full/plain ratios (each progressive run follows
// its plain run, so the pair shares the machine's load); `--timeline`: each
// run's loader timeline and where the progressive full-detail time goes past
// its floor (line lag: the stream's last byte after its floor; then the
// last chunk's decoding, applying, normals, the final draw; with the
// worker, when it had the last chunk's topology replayed and its positions
// decoded, from its own marks in the loader's timeline), with the
// main-thread totals of the whole load (coarse parse, decode, apply,
// normals, draws), and after each load 5 more frames of the scene: their
// wall median and the CPU ms per frame of Chromium's GPU process, where
// SwiftShader draws (load moves it far less than wall times). Exit 1 on a
// failure.

import { execFileSync } from 'node:child_process';
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
    else if (a === '--hold-ms') o.holdMs = Number(v());
    else if (a === '--no-prepare-frame') o.prepareFrame = false;
    else if (a === '--decode') o.decode = v();
    else if (a === '--cold') o.cold = true;
    else { console.error(`stream-bench.mjs: unknown argument ${a}`); process.exit(2); }
  }
  if (!o.progressive || !o.plain) { console.error('stream-bench.mjs: needs --progressive P.glb --plain F.glb'); process.exit(2); }
  o.modes = { worker: ['worker'], main: ['main'], both: ['worker', 'main'] }[o.decode || 'worker'];
  if (!o.modes) { console.error(`stream-bench.mjs: --decode ${o.decode}: worker, main or both`); process.exit(2); }
  return o;
}

const sorted = (xs) => [...xs].sort((a, b) => a - b);
// the median (mean of the middle two for an even count), min and max
const stats = (xs) => {
  const s = sorted(xs), n = s.length, m = n % 2 ? s[(n - 1) / 2] : (s[n / 2 - 1] + s[n / 2]) / 2;
  return { median: m, min: s[0], max: s[n - 1] };
};
const spread = (x, d = 0) => `${x.median.toFixed(d)} (${x.min.toFixed(d)} – ${x.max.toFixed(d)})`;

// Where a progressive run's time went (ms; see the top of this file).
function breakdown(prog, floorFull) {
  const at = (what) => { const m = prog.timeline.find((x) => x.what === what); return m ? m.t : NaN; };
  const full = prog.events[prog.events.length - 1].t;
  const last = at('stream last bytes');
  const tl = prog.timeline, k = tl.length;
  // marks after the last bytes: decoded K, indices K, vertices K, applied K
  const lastDraw = prog.draws[prog.draws.length - 1];
  const tail = { decode: NaN, apply: NaN, draw: lastDraw.ms };
  const dec = tl.findIndex((x, i) => i > 0 && x.what.startsWith('decoded ') && x.t >= last);
  if (dec >= 0) {
    tail.decode = tl[dec].t - last;
    const applied = tl.slice(dec).find((x) => x.what.startsWith('applied '));
    tail.apply = applied ? applied.t - tl[dec].t : NaN;
  }
  // the worker's own marks of the last chunk (its topology replayed, its
  // positions decoded; NaN on the main thread), after the last byte
  const lastWorker = (what) => { const m = tl.filter((x) => x.what.startsWith(`worker ${what} `)).pop(); return m ? m.t - last : NaN; };
  return {
    lag: last - floorFull, tail: full - last, tailDecode: tail.decode, tailApply: tail.apply, finalDraw: tail.draw,
    workerReplayed: lastWorker('replayed'), workerDecoded: lastWorker('decoded'),
    // bytes the final draw handed to WebGL buffers (MB)
    finalUpload: lastDraw.uploaded / 1e6,
    parse: at('coarse parsed') - at('coarse bytes'), decode: prog.spent.decode, apply: prog.spent.apply,
    normals: prog.spent.normals, order: prog.spent.order, worker: prog.spent.worker || 0, draws: prog.draws.length, drawMs: prog.draws.reduce((a, d) => a + d.ms, 0), marks: k,
  };
}

// With the worker: when it had the last chunk's topology replayed and its
// positions decoded, ms after the last byte (negative: before it).
const workerTail = (q) => (Number.isFinite(q.workerDecoded)
  ? ` = the worker's last replay at ${q.workerReplayed.toFixed(0)}, its positions at ${q.workerDecoded.toFixed(0)}, then the page` : '');

// CPU ms (user + system) spent so far by this process's Chromium GPU
// processes (SwiftShader draws there): a frame's cost that the machine's
// load moves far less than its wall time. NaN without /proc.
function gpuCpuMs() {
  const below = (pid) => {
    let kids = [];
    try { kids = execFileSync('pgrep', ['-P', String(pid)], { encoding: 'utf8' }).trim().split(/\s+/).filter(Boolean); } catch { /* none */ }
    return kids.flatMap((k) => [k, ...below(k)]);
  };
  let ticks = 0, found = false;
  for (const pid of below(process.pid)) {
    try {
      if (!fs.readFileSync(`/proc/${pid}/cmdline`, 'utf8').includes('--type=gpu-process')) continue;
      const f = fs.readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
      ticks += Number(f[11]) + Number(f[12]);
      found = true;
    } catch { /* gone */ }
  }
  // (USER_HZ is 100 on Linux)
  return found ? ticks * 10 : NaN;
}

// The scene drawn FRAMES more times: the wall median of a frame and the
// GPU processes' CPU ms per frame.
const FRAMES = 5;
async function frameCost(page) {
  const c0 = gpuCpuMs();
  const wall = await page.evaluate((n) => window.frameMs(n), FRAMES);
  return { wall, cpu: (gpuCpuMs() - c0) / FRAMES };
}

const LOADER = ['index.js', 'lgpm.js', 'order.js', 'remote.js', 'worker.js'].map((f) => `../../crates/lodgen/web/three/${f}`);

// One progressive load (after the plain run `plain` and its frame cost):
// logged, and added to `runs`.
function progressiveRun(o, r, mode, runs, plain, plainFrame, prog, progFrame, requests) {
  const floorOf = (bytes) => o.latency + (bytes * 8) / (o.mbit * 1e3);
  const mine = requests.filter((q) => q.path === '/progressive.glb');
  const bytes = mine.length, sent = mine.reduce((n, q) => n + q.sent, 0);
  const full = prog.events[prog.events.length - 1].t;
  runs.first.push(prog.firstPixel.t);
  runs.full.push(full);
  runs.ratio.push(full / plain.t);
  runs.firstRatio.push(prog.firstPixel.t / plain.t);
  const parts = breakdown(prog, floorOf(prog.fullBytes));
  runs.parts.push(parts);
  parts.frame = progFrame.wall;
  parts.frameCpu = progFrame.cpu;
  const tag = o.modes.length > 1 ? ` [${mode}]` : '';
  console.log(`run ${r + 1}${tag}: plain ${plain.t.toFixed(0)} ms (${plain.drawn} triangles); progressive (decoded in ${prog.decodedIn}) first pixel ` +
    `${prog.firstPixel.t.toFixed(0)} ms (${prog.firstPixel.drawn} triangles), full ${full.toFixed(0)} ms ` +
    `(${prog.events[prog.events.length - 1].drawn} triangles; ${bytes} request(s), ${sent} bytes sent); full/plain ${(full / plain.t).toFixed(2)}`);
  if (o.timeline) {
    console.log('  timeline: ' + prog.timeline.map((m) => `${m.what} ${m.t.toFixed(0)} ms (${m.bytes} B)`).join(', ') +
      '; drawn: ' + prog.events.map((e) => `${e.records} records ${e.t.toFixed(0)} ms`).join(', ') +
      '; draws: ' + prog.draws.map((d) => `at ${d.t.toFixed(0)} ${d.ms.toFixed(0)} ms`).join(', '));
    console.log(`  plain: loaded ${(plain.loaded - floorOf(fs.statSync(o.plain).size)).toFixed(0)} ms past its floor, draw ${plain.drawMs.toFixed(0)} ms, then a frame ${plainFrame.wall.toFixed(0)} ms, GPU CPU ${plainFrame.cpu.toFixed(0)} ms ` +
      `(progressive at full detail ${progFrame.wall.toFixed(0)} ms, GPU CPU ${progFrame.cpu.toFixed(0)} ms); ` +
      `progressive past its floor: line lag ${parts.lag.toFixed(0)} ms, then ${parts.tail.toFixed(0)} ms (decode ${parts.tailDecode.toFixed(0)}${workerTail(parts)}, ` +
      `apply + normals ${parts.tailApply.toFixed(0)}, final draw ${parts.finalDraw.toFixed(0)} uploading ${parts.finalUpload.toFixed(2)} MB; plain's draw ` +
      `${(plain.uploaded / 1e6).toFixed(2)} MB); whole load: parse ${parts.parse.toFixed(0)}, ` +
      `decode ${parts.decode.toFixed(0)} (worker ${parts.worker.toFixed(0)}), apply ${parts.apply.toFixed(0)}, normals ${parts.normals.toFixed(0)}, draw order ${parts.order.toFixed(0)}, ${parts.draws} draws ${parts.drawMs.toFixed(0)} ms`);
  }
}

// The medians of one decoder's runs (the JSON's fields; see main).
function summary(o, runs, tag) {
  const med = (f, from = runs.parts) => stats(from.map(f)).median;
  const res = {
    name: o.name, decode: tag, mbit: o.mbit, latencyMs: o.latency, runs: o.runs,
    plainBytes: fs.statSync(o.plain).size, progressiveBytes: fs.statSync(o.progressive).size,
    plain: stats(runs.plain), firstPixel: stats(runs.first), fullDetail: stats(runs.full),
    fullRatio: stats(runs.ratio), firstRatio: stats(runs.firstRatio),
    // medians over the runs, ms (see breakdown)
    parts: Object.fromEntries(Object.keys(runs.parts[0]).map((k) => [k, med((p) => p[k])])),
    plainParts: Object.fromEntries(['lag', 'draw', 'upload', 'frame', 'frameCpu'].map((k) => [k, med((p) => p[k], runs.plainParts)])),
  };
  res.plainMs = res.plain.median;
  res.firstPixelMs = res.firstPixel.median;
  res.fullDetailMs = res.fullDetail.median;
  const name = o.modes.length > 1 ? `${o.name} [decoded in ${tag}]` : o.name;
  console.log(`${name}, ${o.runs} runs, median (min – max): plain ${spread(res.plain)} ms, first pixel ${spread(res.firstPixel)} ms, ` +
    `full ${spread(res.fullDetail)} ms; run by run full/plain ${spread(res.fullRatio, 2)}, first/plain ${spread(res.firstRatio, 2)}`);
  if (o.timeline) {
    const q = res.parts;
    console.log(`${name} medians: plain past its floor: loaded +${res.plainParts.lag.toFixed(0)} ms, draw ${res.plainParts.draw.toFixed(0)} ms; ` +
      `progressive full past its floor: line lag ${q.lag.toFixed(0)} ms, after the last byte ${q.tail.toFixed(0)} ms (decode ${q.tailDecode.toFixed(0)}${workerTail(q)}, ` +
      `apply + normals ${q.tailApply.toFixed(0)}, final draw ${q.finalDraw.toFixed(0)} uploading ${q.finalUpload.toFixed(2)} MB, ` +
      `plain's ${res.plainParts.upload.toFixed(2)} MB); whole load main thread: parse ${q.parse.toFixed(0)}, ` +
      `decode ${q.decode.toFixed(0)} (the worker's own ${q.worker.toFixed(0)}), apply ${q.apply.toFixed(0)}, normals ${q.normals.toFixed(0)}, draw order ${q.order.toFixed(0)}, ${q.draws} draws ${q.drawMs.toFixed(0)} ms; ` +
      `a frame once loaded: plain ${res.plainParts.frame.toFixed(0)} ms (GPU process CPU ${res.plainParts.frameCpu.toFixed(0)} ms), ` +
      `progressive ${q.frame.toFixed(0)} ms (GPU process CPU ${q.frameCpu.toFixed(0)} ms)`);
  }
  return res;
}

async function main() {
  const o = parseArgs(process.argv.slice(2));
  const routes = {
    '/': { type: 'text/html; charset=utf-8', body: Buffer.from(HTML) },
    '/page.js': { type: 'text/javascript; charset=utf-8', body: await bundle('three-lod-page.js', LOADER) },
    // the loader's decoder worker, where the page's bundle looks for it
    '/worker.js': { type: 'text/javascript; charset=utf-8', body: await bundle('../../crates/lodgen/web/three/worker.js', LOADER), cache: true },
    '/progressive.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.progressive) },
    '/plain.glb': { type: 'model/gltf-binary', body: fs.readFileSync(o.plain) },
  };
  const requests = [];
  const server = await startServer(routes, requests, { bitsPerSecond: o.mbit * 1e6, latencyMs: o.latency });
  const errors = [];
  const browser = await launch(errors);
  const newRuns = () => ({ plain: [], first: [], full: [], ratio: [], firstRatio: [], parts: [], plainParts: [] });
  const runs = Object.fromEntries(o.modes.map((m) => [m, newRuns()]));
  const plainFloor = o.latency + (fs.statSync(o.plain).size * 8) / (o.mbit * 1e3);
  try {
    const page = browser.page;
    // the page too comes over the slow line (once, before any timing)
    const base = `http://127.0.0.1:${server.address().port}`;
    await page.goto(`${base}/`, { waitUntil: 'load', timeout: 120_000 });
    await page.waitForFunction(() => window.pageReady === true, undefined, { timeout: 120_000 });
    for (let r = 0; r < o.runs; r++) {
      const plain = await page.evaluate((u) => window.runPlain(u, { pixels: false }), `${base}/plain.glb`);
      const plainFrame = await frameCost(page);
      const order = r % 2 ? [...o.modes].reverse() : o.modes;
      for (const mode of order) {
        if (o.cold) {
          await page.goto(`${base}/`, { waitUntil: 'load', timeout: 120_000 });
          await page.waitForFunction(() => window.pageReady === true, undefined, { timeout: 120_000 });
        }
        requests.length = 0;
        const prog = await page.evaluate(([u, render, holdMs, prepareFrame, worker]) => window.runProgressive(u, { hash: false, render, pixels: false, holdMs, prepareFrame, worker }),
          [`${base}/progressive.glb`, o.render, o.holdMs, o.prepareFrame !== false, mode === 'main' ? false : undefined]);
        const progFrame = await frameCost(page);
        if (prog.decodedIn !== mode) errors.push(`run ${r + 1}: decoded in ${prog.decodedIn}, not ${mode}${prog.workerError ? ` (${prog.workerError})` : ''}`);
        runs[mode].plain.push(plain.t);
        runs[mode].plainParts.push({ lag: plain.loaded - plainFloor, draw: plain.drawMs, upload: plain.uploaded / 1e6, frame: plainFrame.wall, frameCpu: plainFrame.cpu });
        progressiveRun(o, r, mode, runs[mode], plain, plainFrame, prog, progFrame, requests);
        if (prog.events[prog.events.length - 1].drawn !== plain.drawn) errors.push(`full detail draws ${prog.events[prog.events.length - 1].drawn} triangles, plain ${plain.drawn}`);
      }
    }
  } finally {
    await browser.close();
    server.close();
  }
  const results = o.modes.map((m) => summary(o, runs[m], m));
  // the first decoder's figures, and each one's under `decoders`
  const res = { ...results[0], decoders: Object.fromEntries(o.modes.map((m, i) => [m, results[i]])) };
  if (o.json) fs.writeFileSync(o.json, JSON.stringify(res, null, 2));
  const real = errors.filter((e) => !/\(net::ERR_ABORTED\)$/.test(e));
  if (real.length) throw new Error(real.join('; '));
}

main().catch((e) => {
  console.error(`stream-bench.mjs: ${e.stack || e}`);
  process.exit(1);
});
