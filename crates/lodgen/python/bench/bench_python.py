"""lodgen from Python against the same call in Rust, pyfqmr and
fast-simplification (when installed), on one mesh to one ratio.

    cargo build --release -p lodgen --example simplify_timing
    python crates/lodgen/python/bench/bench_python.py [MESH] [--ratio 0.02] [--rounds 7]

(`cargo xtask bench --python` builds both and runs this in a venv.)

Rounds alternate between the contenders; figures are medians of the call
alone (no file reading): wall time and CPU time of the process (every
thread; lodgen runs on all cores, the peers on one). lodgen runs twice:
with its default `measure="on"` (the call measures its level's error, both
directions, exact distances) and with `measure="off"` (levels only, as the
peers). Every tool's output is then measured the same way, with
lodgen.measure against the input, at the triangle count it reached.
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


def timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def contenders(v, f, ratio, rust, path):
    """(name, run) pairs; run() returns (mesh or None, wall s, cpu s)."""
    target = int(len(f) * ratio)
    out = []
    for m in ("on", "off"):

        def py(m=m):
            r, wall, cpu = timed(lambda: lodgen.simplify(v, f, levels=[ratio], measure=m))
            return (r.levels[0].vertices, r.levels[0].faces), wall, cpu

        out.append((f"lodgen Python, measure={m}", py))
    if rust is not None:
        for m in ("on", "off"):

            def rs(m=m):
                cmd = [rust, path, repr(ratio), "1", "--measure", m]
                line = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
                r = json.loads(line.splitlines()[-1])
                return None, r["seconds"], r["cpu_seconds"]

            out.append((f"lodgen Rust, measure={m}", rs))
    try:
        import pyfqmr
    except ImportError:
        pyfqmr = None
    try:
        import fast_simplification
    except ImportError:
        fast_simplification = None
    if pyfqmr is not None:

        def fq():
            def run():
                s = pyfqmr.Simplify()
                s.setMesh(v.astype(np.float64), f.astype(np.int32))
                s.simplify_mesh(target_count=target, aggressiveness=7, preserve_border=True, verbose=False)
                return s.getMesh()[:2]

            return timed(run)

        out.append((f"pyfqmr {getattr(pyfqmr, '__version__', '')}".strip(), fq))
    if fast_simplification is not None:

        def fs():
            return timed(
                lambda: fast_simplification.simplify(v, f.astype(np.int32), target_reduction=1 - ratio)
            )

        version = getattr(fast_simplification, "__version__", "")
        out.append((f"fast-simplification {version}".strip(), fs))
    return out


def main() -> int:
    p = argparse.ArgumentParser()
    default_mesh = pathlib.Path(os.environ.get("LODGEN_ASSETS", ROOT.parent / "shared/assets")) / "bunny.obj"
    p.add_argument("mesh", nargs="?", default=str(default_mesh))
    p.add_argument("--ratio", type=float, default=0.02)
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--rust", default=str(ROOT / "target/release/examples/simplify_timing"))
    a = p.parse_args()
    rust = a.rust if os.path.exists(a.rust) else None
    if rust is None:
        print(f"note: {a.rust} not found: no Rust figures (cargo build --release -p lodgen --example simplify_timing)")

    v, f = lodgen.read(a.mesh)
    runs = contenders(v, f, a.ratio, rust, a.mesh)
    wall = {name: [] for name, _ in runs}
    cpu = {name: [] for name, _ in runs}
    meshes = {}
    for _ in range(a.rounds):
        for name, run in runs:
            mesh, w, c = run()
            wall[name].append(w)
            cpu[name].append(c)
            if mesh is not None:
                meshes.setdefault(name, mesh)
    errors = {name: lodgen.measure((v, f), m) for name, m in meshes.items()}

    print(
        f"{pathlib.Path(a.mesh).name}: {len(f)} triangles -> {a.ratio:g} ({int(len(f) * a.ratio)}), "
        f"median of {a.rounds} alternating rounds, {os.cpu_count()} cores, load average "
        f"{os.getloadavg()[0]:.2f}"
    )
    print(f"{'':34} {'wall ms':>8} {'cpu ms':>8} {'triangles':>9} {'Hausdorff %':>11} {'RMS %':>7}")
    base = "lodgen Python, measure=on"
    for name, _ in runs:
        w, c = statistics.median(wall[name]), statistics.median(cpu[name])
        same = name.replace("Rust", "Python")
        e = errors.get(name) or errors.get(same)
        tris = len((meshes.get(name) or meshes[same])[1])
        print(
            f"{name:34} {1000 * w:8.1f} {1000 * c:8.1f} {tris:9d} {e.hausdorff_percent:11.4f} "
            f"{e.rms_percent:7.4f}   wall {w / statistics.median(wall[base]):.2f}x, "
            f"cpu {c / statistics.median(cpu[base]):.2f}x lodgen Python measure=on"
        )
    if rust is not None:
        for m in ("on", "off"):
            py, rs = f"lodgen Python, measure={m}", f"lodgen Rust, measure={m}"
            print(
                f"Python / Rust, measure={m}: wall {statistics.median(wall[py]) / statistics.median(wall[rs]):.3f}x, "
                f"cpu {statistics.median(cpu[py]) / statistics.median(cpu[rs]):.3f}x"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
