"""Shared fixtures: generated meshes, the shared test meshes and the
``lodgen`` command (``$LODGEN_BIN``, else target/release or target/debug).
Missing meshes or binary skip a test, and fail it when CI=true."""

import os
import pathlib
import shutil

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[4]


def _missing(what: str):
    if os.environ.get("CI") == "true":
        pytest.fail(f"{what} is missing (CI=true)")
    pytest.skip(f"{what} not found")


def torus(big_r=1.0, r=0.35, n=48, m=24, dtype=np.float64):
    """A closed torus of 2·n·m triangles."""
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    u = 2 * np.pi * i / n
    v = 2 * np.pi * j / m
    x = (big_r + r * np.cos(v)) * np.cos(u)
    y = (big_r + r * np.cos(v)) * np.sin(u)
    z = r * np.sin(v)
    vertices = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype(dtype)
    a = (i * m + j).ravel()
    b = (((i + 1) % n) * m + j).ravel()
    c = (((i + 1) % n) * m + (j + 1) % m).ravel()
    d = (i * m + (j + 1) % m).ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return vertices, faces.astype(np.int64)


def write_obj(path, vertices, faces):
    with open(path, "w") as f:
        for p in vertices:
            f.write(f"v {float(p[0])!r} {float(p[1])!r} {float(p[2])!r}\n")
        for t in faces:
            f.write(f"f {t[0] + 1} {t[1] + 1} {t[2] + 1}\n")


@pytest.fixture(scope="session")
def lodgen_bin():
    env = os.environ.get("LODGEN_BIN")
    candidates = [pathlib.Path(env)] if env else []
    candidates += [ROOT / "target/release/lodgen", ROOT / "target/debug/lodgen"]
    for c in candidates:
        if c.is_file():
            return str(c)
    found = shutil.which("lodgen")
    if found:
        return found
    _missing("the lodgen binary (set LODGEN_BIN)")


def shared_asset(name: str) -> pathlib.Path:
    base = os.environ.get("LODGEN_ASSETS")
    path = pathlib.Path(base) / name if base else ROOT.parent / "shared/assets" / name
    if not path.is_file():
        _missing(f"test mesh {path}")
    return path


@pytest.fixture
def bunny():
    return shared_asset("bunny.obj")
