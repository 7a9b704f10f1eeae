"""lodgen.build mapped over a directory on a Dask LocalCluster with several
worker processes gives the bytes of the command's batch, and per-file
reports (a broken file reported, not raised)."""

import json
import pathlib
import subprocess

import pytest

import lodgen
from conftest import torus, write_obj

distributed = pytest.importorskip("distributed")


def make_inputs(root: pathlib.Path) -> pathlib.Path:
    d = root / "in"
    (d / "sub").mkdir(parents=True)
    for k, (n, m) in enumerate([(48, 24), (32, 16), (64, 20), (20, 10)]):
        v, f = torus(1.0 + 0.2 * k, 0.3, n, m)
        write_obj(d / ("sub" if k % 2 else ".") / f"torus{k}.obj", v, f)
    (d / "sub" / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 3\n")
    return d


def test_dask_build_equals_the_command_batch(tmp_path, lodgen_bin):
    from dask.distributed import Client, LocalCluster

    from lodgen.dask import build_on_dask

    inputs = make_inputs(tmp_path)
    cli = subprocess.run(
        [lodgen_bin, str(inputs), "--out-dir", str(tmp_path / "cli"), "--levels", "50%,5%",
         "--jobs", "2", "--report", str(tmp_path / "cli.json"), "-q"],
        capture_output=True, text=True,
    )
    assert cli.returncode != 0  # the broken file
    cli_report = json.loads((tmp_path / "cli.json").read_text())

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        report = build_on_dask(client, [inputs], tmp_path / "dask", threads=1,
                               levels=[0.5, 0.05])
    assert (report["built"], report["failed"]) == (4, 1)
    by_input = {f["input"]: f for f in report["files"]}
    for c in cli_report["files"]:
        d = by_input[c["input"]]
        assert d["status"] == c["status"], (c, d)
        rel = pathlib.Path(c["output"]).relative_to(tmp_path / "cli")
        assert pathlib.Path(d["output"]) == tmp_path / "dask" / rel
        if c["status"] == "built":
            assert pathlib.Path(d["output"]).read_bytes() == pathlib.Path(c["output"]).read_bytes()
            assert d["report"]["meshes"] == c["report"]["meshes"]
        else:
            assert d["error"] == c["error"]
            assert not pathlib.Path(d["output"]).exists()
    # Python's own batch: the same files, statuses and bytes again.
    py = lodgen.batch([inputs], tmp_path / "py", levels=[0.5, 0.05], jobs=2)
    assert (py["built"], py["failed"]) == (4, 1)
    for f in py["files"]:
        if f["status"] == "built":
            rel = pathlib.Path(f["output"]).relative_to(tmp_path / "py")
            assert pathlib.Path(f["output"]).read_bytes() == (tmp_path / "cli" / rel).read_bytes()
