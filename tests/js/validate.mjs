#!/usr/bin/env node
// Runs the Khronos glTF-Validator on every .gltf/.glb under DIR (recursively).
//
//   node validate.mjs [--require] [--verbose] DIR
//
// One line per file with its error/warning/info/hint counts; the error
// messages follow when a file has errors (all messages with --verbose).
// External buffers and images are resolved relative to the file.
// Exit status: 1 if any file has errors, or (with --require) if DIR holds no
// glTF file at all; 2 on bad usage.

import fs from 'node:fs';
import path from 'node:path';
import validator from 'gltf-validator';

const SEVERITY = ['error', 'warning', 'info', 'hint'];

function usage(msg) {
  console.error(`validate.mjs: ${msg}\nusage: node validate.mjs [--require] [--verbose] DIR`);
  process.exit(2);
}

function parseArgs(argv) {
  const opts = { require: false, verbose: false, dir: null };
  for (const a of argv) {
    if (a === '--require') opts.require = true;
    else if (a === '--verbose') opts.verbose = true;
    else if (a.startsWith('-')) usage(`unknown option ${a}`);
    else if (opts.dir === null) opts.dir = a;
    else usage(`unexpected argument ${a}`);
  }
  if (opts.dir === null) usage('missing DIR');
  return opts;
}

// Sorted, recursive list of .gltf/.glb files (symlinked directories are not followed).
function findGltf(dir) {
  const out = [];
  const walk = (d) => {
    const entries = fs.readdirSync(d, { withFileTypes: true });
    entries.sort((a, b) => (a.name < b.name ? -1 : a.name > b.name ? 1 : 0));
    for (const e of entries) {
      const p = path.join(d, e.name);
      if (e.isDirectory()) walk(p);
      else if (e.isFile() && /\.(gltf|glb)$/i.test(e.name)) out.push(p);
    }
  };
  walk(dir);
  return out;
}

async function validateFile(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const base = path.dirname(file);
  return validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0, // unlimited
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        let rel;
        try {
          rel = decodeURIComponent(uri);
        } catch (e) {
          reject(new Error(`bad URI ${uri}: ${e.message}`));
          return;
        }
        fs.readFile(path.resolve(base, rel), (err, data) => {
          if (err) reject(err.toString());
          else resolve(new Uint8Array(data));
        });
      }),
  });
}

function fmtMessage(m) {
  const where = m.pointer ? ` at ${m.pointer}` : m.offset !== undefined ? ` at byte ${m.offset}` : '';
  return `    ${SEVERITY[m.severity] ?? m.severity} ${m.code}${where}: ${m.message}`;
}

async function main() {
  const opts = parseArgs(process.argv.slice(2));
  let files = [];
  if (fs.existsSync(opts.dir)) {
    if (!fs.statSync(opts.dir).isDirectory()) usage(`${opts.dir} is not a directory`);
    files = findGltf(opts.dir);
  }
  if (files.length === 0) {
    const msg = `validate: no .gltf/.glb file under ${opts.dir}`;
    if (opts.require) {
      console.error(`${msg} (--require given): FAIL`);
      process.exit(1);
    }
    console.log(`${msg}; nothing to validate`);
    return;
  }
  console.log(`validate: glTF-Validator ${validator.version()} on ${files.length} file(s) under ${opts.dir}`);
  let failed = 0;
  for (const file of files) {
    const rel = path.relative(opts.dir, file) || file;
    let report;
    try {
      report = await validateFile(file);
    } catch (e) {
      failed++;
      console.log(`FAIL ${rel}: validator could not read the file: ${e?.message ?? e}`);
      continue;
    }
    const is = report.issues;
    const bad = is.numErrors > 0;
    if (bad) failed++;
    console.log(
      `${bad ? 'FAIL' : 'ok  '} ${rel}: ${is.numErrors} errors, ${is.numWarnings} warnings, ` +
        `${is.numInfos} infos, ${is.numHints} hints`,
    );
    for (const m of is.messages) {
      if (m.severity === 0 || opts.verbose) console.log(fmtMessage(m));
    }
  }
  console.log(`validate: ${files.length - failed} passed, ${failed} failed`);
  if (failed > 0) process.exit(1);
}

main().catch((e) => {
  console.error(`validate: ${e?.stack ?? e}`);
  process.exit(1);
});
