"""lodgen from Python against the same call in Rust, pyfqmr and
fast-simplification (when installed), on one mesh to one ratio.

    cargo build --release -p lodgen --example simplify_timing
    python crates/lodgen/python/bench/bench_python.py [MESH] [--ratio 0.02] [--rounds 7]

Rounds alternate between the contenders; times are medians of the call
alone (no file reading). lodgen's time includes measuring its level's
error (what `lodgen.simplify` does); the others' error is measured
afterwards with lodgen.measure, at the triangle count each reached.
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import time

import numpy as np

import lodgen

ROOT = pathlib.Path(__file__).resolve().parents[4]


def main() -> int:
    p = argparse.ArgumentParser()
    default_mesh = pathlib.Path(os.environ.get("LODGEN_ASSETS", ROOT.parent / "shared/assets")) / "bunny.obj"
    p.add_argument("mesh", nargs="?", default=str(default_mesh))
    p.add_argument("--ratio", type=float, default=0.02)
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--rust", default=str(ROOT / "target/release/examples/simplify_timing"))
    a = p.parse_args()

    v, f = lodgen.read(a.mesh)
    target = int(len(f) * a.ratio)
    times = {}
    errors = {}
    counts = {}

    def add(name, seconds, mesh=None, err=None):
        times.setdefault(name, []).append(seconds)
        if mesh is not None and name not in errors:
            counts[name] = len(mesh[1])
            errors[name] = err if err is not None else lodgen.measure((v, f), mesh)

    try:
        import pyfqmr
    except ImportError:
        pyfqmr = None
    try:
        import fast_simplification
    except ImportError:
        fast_simplification = None

    for _ in range(a.rounds):
        t0 = time.perf_counter()
        r = lodgen.simplify(v, f, levels=[a.ratio])
        add("lodgen (Python)", time.perf_counter() - t0, (r.levels[0].vertices, r.levels[0].faces), r.levels[0].errors)
        if os.path.exists(a.rust):
            out = subprocess.run([a.rust, a.mesh, repr(a.ratio), "1"], capture_output=True, text=True, check=True)
            add("lodgen (Rust, same call)", json.loads(out.stdout.splitlines()[-1])["seconds"])
        if pyfqmr is not None:
            t0 = time.perf_counter()
            s = pyfqmr.Simplify()
            s.setMesh(v.astype(np.float64), f.astype(np.int32))
            s.simplify_mesh(target_count=target, aggressiveness=7, preserve_border=True, verbose=False)
            mv, mf, _ = s.getMesh()
            add(f"pyfqmr {getattr(pyfqmr, '__version__', '')}".strip(), time.perf_counter() - t0, (mv, mf))
        if fast_simplification is not None:
            t0 = time.perf_counter()
            mv, mf = fast_simplification.simplify(v, f.astype(np.int32), target_reduction=1 - a.ratio)
            add("fast-simplification", time.perf_counter() - t0, (mv, mf))

    print(f"{pathlib.Path(a.mesh).name}: {len(f)} triangles -> {a.ratio:g} ({target}), median of {a.rounds} alternating rounds")
    print(f"{'':28} {'time ms':>9} {'triangles':>10} {'hausdorff %':>12} {'rms %':>8}")
    py = statistics.median(times["lodgen (Python)"])
    for name, ts in times.items():
        m = statistics.median(ts)
        e = errors.get(name) or errors["lodgen (Python)"]
        c = counts.get(name, counts["lodgen (Python)"])
        print(f"{name:28} {1000 * m:9.1f} {c:10d} {e.hausdorff_percent:12.4f} {e.rms_percent:8.4f}   ({m / py:.2f}x lodgen from Python)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
