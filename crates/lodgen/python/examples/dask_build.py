"""Build LODs of every mesh under a directory on a Dask cluster.

    python dask_build.py meshes/ lods/ --workers 2 --levels 0.5,0.1,0.02

Starts a LocalCluster of worker processes (or connects to --scheduler
tcp://host:8786, e.g. one started by dask-jobqueue or on Kubernetes), maps
lodgen.build over the files (one task each), prints a line per file and
exits non-zero if any failed. Outputs are byte-identical to
`lodgen meshes/ --out-dir lods/`.
"""

import argparse
import os
import sys

from dask.distributed import Client, LocalCluster

from lodgen.dask import build_on_dask


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("inputs", nargs="+", help="files, directories or glob patterns")
    p.add_argument("out_dir")
    p.add_argument("--workers", type=int, default=2, help="local worker processes")
    p.add_argument("--scheduler", help="address of an existing Dask scheduler")
    p.add_argument("--levels", default="0.5,0.1,0.02")
    a = p.parse_args()
    levels = [float(x) if "." in x else int(x) for x in a.levels.split(",")]
    if a.scheduler:
        client, cluster = Client(a.scheduler), None
        threads = None
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
        threads = max(1, (os.cpu_count() or 1) // a.workers)
    try:
        report = build_on_dask(client, a.inputs, a.out_dir, threads=threads, levels=levels)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    for f in report["files"]:
        line = f"{f['status']:>7}  {f['seconds']:6.2f} s  {f['input']}"
        if f["error"]:
            line += f": {f['error']}"
        print(line)
    print(f"{report['built']} built, {report['failed']} failed")
    return 1 if report["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
