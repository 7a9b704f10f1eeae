"""Batch mode: N generated meshes (log-uniform 1k-200k triangles, noisy tori
as binary PLY), `lodgen DIR --out-dir OUT --jobs 2` against `--jobs 1`
(alternating, --force), then a re-run with nothing changed.

    cargo build --release -p lodgen
    python crates/lodgen/python/bench/bench_batch.py [--count 200] [--rounds 2] [--dir /tmp/lodgen-batch]
"""

import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[4]


def noisy_torus(triangles: int, rng) -> tuple:
    m = max(3, int(round((triangles / 4) ** 0.5)))
    n = max(3, triangles // (2 * m))
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    u, v = 2 * np.pi * i / n, 2 * np.pi * j / m
    r = 0.35 * (1 + 0.02 * rng.standard_normal(u.shape))
    p = np.stack([(1 + r * np.cos(v)) * np.cos(u), (1 + r * np.cos(v)) * np.sin(u), r * np.sin(v)], -1)
    a = (i * m + j).ravel()
    b = (((i + 1) % n) * m + j).ravel()
    c = (((i + 1) % n) * m + (j + 1) % m).ravel()
    d = (i * m + (j + 1) % m).ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return p.reshape(-1, 3).astype("<f4"), faces.astype("<i4")


def write_ply(path: pathlib.Path, v, f) -> None:
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    rec = np.zeros(len(f), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    rec["n"], rec["i"] = 3, f
    with open(path, "wb") as out:
        out.write(header.encode())
        out.write(v.tobytes())
        out.write(rec.tobytes())


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--count", type=int, default=200)
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--dir", default="/tmp/lodgen-batch")
    p.add_argument("--lodgen", default=str(ROOT / "target/release/lodgen"))
    a = p.parse_args()
    base = pathlib.Path(a.dir)
    src = base / "in"
    rng = np.random.default_rng(17)
    sizes = np.exp(rng.uniform(np.log(1000), np.log(200000), a.count)).astype(int)
    if not src.exists() or len(list(src.glob("*/*.ply"))) != a.count:
        for k, t in enumerate(sizes):
            d = src / f"group{k % 10}"
            d.mkdir(parents=True, exist_ok=True)
            write_ply(d / f"mesh{k:03d}.ply", *noisy_torus(int(t), rng))
    total = sum(int(t) for t in sizes)
    print(f"{a.count} meshes, about {total} triangles in all ({sizes.min()}-{sizes.max()} each)")
    times = {1: [], 2: []}
    cpu = {1: [], 2: []}
    busy = {1: [], 2: []}
    report = base / "report.json"
    loads = [os.getloadavg()[0]]
    for _ in range(a.rounds):
        for jobs in (1, 2):
            t0, c0 = time.perf_counter(), children_cpu()
            subprocess.run([a.lodgen, str(src), "--out-dir", str(base / "out"), "--jobs", str(jobs),
                            "--force", "-q", "--report", str(report)], check=True)
            times[jobs].append(time.perf_counter() - t0)
            cpu[jobs].append(children_cpu() - c0)
            r = json.loads(report.read_text())
            busy[jobs].append(sum(f["seconds"] for f in r["files"]) / r["seconds"])
            loads.append(os.getloadavg()[0])
    t0 = time.perf_counter()
    out = subprocess.run([a.lodgen, str(src), "--out-dir", str(base / "out"), "--jobs", "2"],
                         check=True, capture_output=True, text=True)
    rerun = time.perf_counter() - t0
    assert f"0 built, {a.count} unchanged" in out.stdout, out.stdout[-300:]
    j1, j2 = statistics.median(times[1]), statistics.median(times[2])
    for jobs in (1, 2):
        runs = ", ".join(f"{t:.2f}" for t in times[jobs])
        cpus = ", ".join(f"{t:.2f}" for t in cpu[jobs])
        files = ", ".join(f"{b:.2f}" for b in busy[jobs])
        print(f"--jobs {jobs}: {statistics.median(times[jobs]):.2f} s wall (runs {runs}; CPU {cpus} s; "
              f"files in progress on average {files})")
    pairs = [b / a for a, b in zip(times[1], times[2])]
    print(f"--jobs 2 / --jobs 1: {j2 / j1:.2f}x (medians); run by run {', '.join(f'{r:.2f}' for r in pairs)}")
    print(f"load average (1 min) during the runs: {min(loads):.2f}-{max(loads):.2f} on {os.cpu_count()} cores")
    print(f"re-run with nothing changed: {rerun:.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
