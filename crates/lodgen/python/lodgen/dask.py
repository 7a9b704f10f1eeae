"""Build many meshes on a Dask ``distributed`` cluster.

``build_on_dask(client, inputs, out_dir, **cli_options)`` expands the
inputs exactly as ``lodgen INPUT... --out-dir DIR`` does (files,
directories, globs; the same relative layout), maps :func:`lodgen.build`
over them as one Dask task per file, and gathers the per-file reports. The
outputs have the bytes of the command's batch. Paths must be visible to
every worker (a shared file system); the cluster can be a ``LocalCluster``,
a ``dask_jobqueue`` cluster (SLURM, PBS, ...) or ``dask_kubernetes``: only
the ``Client`` changes.

    from dask.distributed import Client, LocalCluster
    from lodgen.dask import build_on_dask
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        report = build_on_dask(client, ["meshes/"], "lods/", levels=[0.5, 0.1])
    print(report["built"], report["failed"])
"""

from __future__ import annotations

import os
import time
from typing import Any, Iterable, Optional, Union

import lodgen


def build_one(
    path_in: str, path_out: str, threads: Optional[int], options: dict
) -> dict:
    """One Dask task: ``lodgen.build`` on one file; a failure is reported
    in the result (status "failed", the command's message), not raised,
    so one broken file never stops the others."""
    t0 = time.perf_counter()
    try:
        report = lodgen.build(path_in, path_out, threads=threads, **options)
        status, error = "built", None
    except lodgen.LodgenError as e:
        report, status, error = None, "failed", str(e)
    return {
        "input": path_in,
        "output": path_out,
        "status": status,
        "error": error,
        "seconds": time.perf_counter() - t0,
        "report": report,
    }


def build_on_dask(
    client: Any,
    inputs: Iterable[Union[str, os.PathLike]],
    out_dir: Union[str, os.PathLike],
    *,
    threads: Optional[int] = None,
    **cli_options: Any,
) -> dict:
    """Map :func:`lodgen.build` over ``inputs`` on ``client``'s cluster.

    ``threads``: each task's own threads (default: every core of its
    worker; with several single-threaded workers per machine, cores /
    workers avoids oversubscription). ``cli_options`` are the command's
    flags. Returns ``{"files": [...], "built": n, "failed": n}`` with the
    files in batch order, each as :func:`build_one` returns it.
    """
    pairs = lodgen.expand_inputs(inputs, out_dir)
    futures = client.map(
        build_one,
        [i for i, _ in pairs],
        [o for _, o in pairs],
        threads=threads,
        options=cli_options,
        pure=False,
    )
    files = client.gather(futures)
    return {
        "files": files,
        "built": sum(f["status"] == "built" for f in files),
        "failed": sum(f["status"] == "failed" for f in files),
    }
