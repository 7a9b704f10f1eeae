"""lodgen: levels of detail and progressive meshes with measured error.

Garland-Heckbert quadric pair contraction in which every contraction is
recorded as a Hoppe vertex split, from Python::

    import lodgen, trimesh
    mesh = trimesh.load("bunny.obj")
    result = lodgen.simplify(mesh, levels=[0.5, 0.1, 0.02])
    for level in result.levels:
        print(len(level.faces), level.errors.hausdorff_percent)

Keyword options are the ``lodgen`` command's flags with ``_`` for ``-``
(``tau="0.5%"``, ``boundary="locked"``, ``method="qem-curvature"``,
``uniform_weights=True``; see ``lodgen --help`` for every one with its
default and unit), parsed by the command's own parser, so defaults and
error messages are the command's. Every call releases the GIL while it
works. Errors raise :class:`LodgenError` (a ``ValueError``) with the
command's message.
"""

from __future__ import annotations

import json
import os
import sys
from dataclasses import dataclass
from typing import Any, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _lodgen
from ._lodgen import LodgenError

__all__ = [
    "Errors",
    "Level",
    "LodgenError",
    "ProgressiveMesh",
    "SimplifyResult",
    "batch",
    "build",
    "expand_inputs",
    "measure",
    "read",
    "simplify",
]

__version__: str = _lodgen.__version__

#: The dtype of :attr:`ProgressiveMesh.splits`: one record per vertex split,
#: coarse to fine. Split ``k`` restores vertex ``v0`` at ``p0`` and moves
#: ``v1`` from ``p_merged`` back to ``p1``; it restores the ``n_faces``
#: triangles ``ProgressiveMesh.split_faces[first_face:first_face + n_faces]``
#: (numbered on from the mesh's current triangles, in that order) and moves
#: the ``n_corners`` corners ``ProgressiveMesh.split_corners[first_corner:
#: first_corner + n_corners]`` (triangle, slot) from ``v1`` back to ``v0``;
#: ``error`` is the contraction's quadric error.
SPLIT_DTYPE = np.dtype(
    [
        ("v1", "<u4"),
        ("v0", "<u4"),
        ("p1", "<f4", (3,)),
        ("p_merged", "<f4", (3,)),
        ("p0", "<f4", (3,)),
        ("n_faces", "<u4"),
        ("first_face", "<u8"),
        ("n_corners", "<u4"),
        ("first_corner", "<u8"),
        ("error", "<f4"),
    ]
)

MeshLike = Any  # a trimesh.Trimesh, or anything with .vertices and .faces

_DEFAULT_LEVELS = (0.5, 0.1, 0.02)

#: The most threads ``build(threads=...)`` starts (more is a typo, not a
#: machine: each is an OS thread).
_MAX_THREADS = 1024


#: Options of the command that mean nothing for a call returning arrays
#: (:func:`simplify`, :class:`ProgressiveMesh`): refused there, not ignored.
_FILE_OPTIONS = (
    "report",
    "quantize",
    "compress",
    "progressive",
    "jobs",
    "force",
    "strict",
    "quiet",
    "verbose",
)


def _flag_value(key: str, value: Any) -> str:
    if key in ("levels", "max_error") and isinstance(value, (bytes, bytearray)):
        raise LodgenError(f"{key}: a list of levels or a string, not bytes {value!r}")
    if key in ("levels", "max_error") and not isinstance(value, str):
        try:
            value = list(value)
        except TypeError:
            raise LodgenError(
                f"{key}= takes a list (levels=[0.5, 0.1]) or a string, not {value!r}"
            ) from None
    if key == "levels" and not isinstance(value, str):
        items = []
        for v in value:
            if isinstance(v, (bool, np.bool_)):
                raise LodgenError(f"--levels: {v!r} is not a ratio or a triangle count")
            if isinstance(v, (int, np.integer)):
                items.append(str(int(v)))
            elif isinstance(v, str):
                items.append(v)
            else:
                items.append(repr(float(v)))
        return ",".join(items)
    if key == "max_error" and not isinstance(value, str):
        if any(isinstance(v, (bool, np.bool_)) for v in value):
            raise LodgenError(f"--max-error: {value!r}: bounds are numbers, not booleans")
        return ",".join(v if isinstance(v, str) else f"{float(v)!r}%" for v in value)
    if key == "attribute_weights" and isinstance(value, dict):
        return ",".join(f"{k}={float(v)!r}" for k, v in value.items())
    return str(value)


def _argv(options: dict, arrays: bool = False) -> List[str]:
    """The command line's flags for keyword options (``arrays``: for a call
    that returns arrays, where the file options are refused)."""
    argv: List[str] = []
    if "levels" in options and "max_error" in options:
        raise LodgenError("levels= and max_error= cannot be used together")
    for key, value in options.items():
        if key in ("input", "inputs", "output", "out_dir"):
            raise LodgenError(f"{key}= is not an option here; pass paths as arguments")
        if arrays and key in _FILE_OPTIONS:
            raise LodgenError(
                f"{key}= is an option of the files the command writes; "
                "lodgen.build(path_in, path_out, ...) takes it"
            )
        if isinstance(value, np.bool_):
            value = bool(value)
        if key == "measure" and isinstance(value, bool):
            value = "on" if value else "off"
        if key == "reach" and (value is None or value is False):
            value = "off"  # (on by default: reach=False turns it off)
        if value is None or value is False:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            argv.append(flag)
        else:
            # one word, so that a value starting with "-" (levels=[-0.5],
            # tau="-1") reaches the option's own check, not the parser as a flag
            argv.append(f"{flag}={_flag_value(key, value)}")
    return argv


def _count(value: Any, what: str) -> int:
    """``value`` as a count for the native module: an integer, below 0 taken
    as 0 and above ``sys.maxsize`` as ``sys.maxsize`` (counts are clamped)."""
    try:
        n = int(value)
    except (TypeError, ValueError, OverflowError):
        raise LodgenError(f"{what} must be an integer, not {value!r}") from None
    return min(max(n, 0), sys.maxsize)


def _mesh_arrays(vertices: Any, faces: Any = None) -> Tuple[np.ndarray, np.ndarray, np.dtype]:
    if faces is None:
        if isinstance(vertices, tuple) and len(vertices) == 2:
            vertices, faces = vertices
        elif hasattr(vertices, "vertices") and hasattr(vertices, "faces"):
            vertices, faces = vertices.vertices, vertices.faces
        else:
            raise LodgenError(
                "pass vertices and faces, a (vertices, faces) tuple or a trimesh.Trimesh"
            )
    v = np.asarray(vertices)
    f = np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3:
        raise LodgenError(f"vertices must have shape (n, 3), not {v.shape}")
    if f.ndim != 2 or f.shape[1] != 3:
        raise LodgenError(f"faces must have shape (m, 3), not {f.shape}")
    if not np.issubdtype(v.dtype, np.floating) and not np.issubdtype(v.dtype, np.integer):
        raise LodgenError(f"vertices must be numbers, not {v.dtype}")
    if f.size and not np.issubdtype(f.dtype, np.integer):
        raise LodgenError(f"faces must be integer vertex indices, not {f.dtype}")
    if f.dtype.kind == "u" and f.size and f.max() > np.iinfo(np.int64).max:
        # (int64 would wrap it to a negative index)
        k = int(np.argmax(f.max(axis=1)))
        raise LodgenError(
            f"triangle {k} refers to vertex {int(f[k].max())}, "
            f"but there are only {len(v)} vertices"
        )
    if v.dtype.kind == "f" and v.dtype.itemsize > 4 and v.size:
        big = np.abs(v) > np.finfo(np.float32).max
        if big.any():
            i = int(np.argwhere(big)[0][0])
            raise LodgenError(
                f"vertex {i} has a coordinate beyond float32's range {v[i].tolist()} "
                "(lodgen computes in float32)"
            )
    return (
        np.ascontiguousarray(v, dtype=np.float32),
        np.ascontiguousarray(f, dtype=np.int64),
        v.dtype,
    )


#: A mesh whose first vertex has a coordinate this far from the origin is computed moved to
#: that vertex, rounded (as the command reads such files: ``lodgen.io::FAR_COORDINATE``), and
#: every vertex returned is moved back: a scan in UTM coordinates keeps its detail, which
#: float32 (a step of 0.5 at 5e6) would lose.
FAR_COORDINATE = 8192.0


def _offset_of(vertices: Any, faces: Any = None) -> Optional[np.ndarray]:
    """The offset a mesh is computed moved by (:data:`FAR_COORDINATE`), or None."""
    if faces is None:
        if isinstance(vertices, tuple) and len(vertices) == 2:
            vertices = vertices[0]
        elif hasattr(vertices, "vertices"):
            vertices = vertices.vertices
    v = np.asarray(vertices)
    if v.ndim != 2 or not len(v) or v.dtype.kind not in "fiu":
        return None
    first = v[0].astype(np.float64)
    if not np.isfinite(first).all() or np.abs(first).max() < FAR_COORDINATE:
        return None
    return np.round(first)


def _moved_arrays(
    vertices: Any, faces: Any = None, offset: Optional[np.ndarray] = None
) -> Tuple[np.ndarray, np.ndarray, np.dtype]:
    """:func:`_mesh_arrays` of the mesh less ``offset`` (subtracted in float64)."""
    if offset is None:
        return _mesh_arrays(vertices, faces)
    if faces is None:
        if isinstance(vertices, tuple) and len(vertices) == 2:
            vertices, faces = vertices
        elif hasattr(vertices, "vertices") and hasattr(vertices, "faces"):
            vertices, faces = vertices.vertices, vertices.faces
    v = np.asarray(vertices)
    _, f, dtype = _mesh_arrays(v, faces)
    return np.ascontiguousarray(v.astype(np.float64) - offset, dtype=np.float32), f, dtype


def _moved_back(v: np.ndarray, offset: Optional[np.ndarray], dtype: Any) -> np.ndarray:
    """Vertices computed moved by ``offset``, back where they belong, as ``dtype``."""
    if offset is None:
        return v.astype(dtype, copy=False)
    return (v.astype(np.float64) + offset).astype(dtype, copy=False)


@dataclass(frozen=True)
class Errors:
    """Measured distance between two surfaces (area-weighted samples plus
    every vertex, exact point-triangle distance, both directions), in mesh
    units; the ``*_percent`` properties are % of the reference's
    bounding-box diagonal, as the command prints them."""

    diagonal: float
    hausdorff: float
    mean: float
    rms: float
    a_to_b_max: float
    a_to_b_mean: float
    a_to_b_rms: float
    a_to_b_samples: int
    b_to_a_max: float
    b_to_a_mean: float
    b_to_a_rms: float
    b_to_a_samples: int

    @classmethod
    def _from(cls, t: Sequence[float]) -> "Errors":
        return cls(
            t[0], t[1], t[2], t[3], t[4], t[5], t[6], int(t[7]), t[8], t[9], t[10], int(t[11])
        )

    def percent(self, distance: float) -> float:
        return 100.0 * distance / self.diagonal if self.diagonal > 0 else 0.0

    @property
    def hausdorff_percent(self) -> float:
        return self.percent(self.hausdorff)

    @property
    def mean_percent(self) -> float:
        return self.percent(self.mean)

    @property
    def rms_percent(self) -> float:
        return self.percent(self.rms)


@dataclass(frozen=True)
class Level:
    """One level of detail: its mesh, the splits from the base mesh that
    reach it, and its measured error against the input."""

    vertices: np.ndarray
    faces: np.ndarray
    splits: int
    errors: Errors

    def to_trimesh(self) -> Any:
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)


class ProgressiveMesh:
    """The whole sequence M_n ... M_g of a simplification: a base mesh and
    the vertex splits that refine it back to the (welded) input exactly,
    with a cursor that moves split by split.

    ``ProgressiveMesh(vertices, faces, target_triangles=None, **options)``
    simplifies as far as it can (or to ``target_triangles``) and keeps the
    log; :func:`simplify` returns the one its levels were cut from.
    Vertex and triangle numbers are the progressive ones: vertex ``i`` of
    a mesh is vertex ``vertex_origin[i]`` of the welded input, and
    ``vertex_map`` maps input vertices to welded ones.
    """

    def __init__(
        self,
        vertices: Any = None,
        faces: Any = None,
        *,
        target_triangles: Optional[int] = None,
        _native: Any = None,
        _offset: Optional[np.ndarray] = None,
        **options: Any,
    ) -> None:
        self._offset = _offset
        if _native is None:
            self._offset = _offset_of(vertices, faces)
            v, f, _ = _moved_arrays(vertices, faces, self._offset)
            if target_triangles is not None:
                t = _count(target_triangles, "target_triangles")
                if int(target_triangles) < 0:
                    raise LodgenError(
                        f"target_triangles must be a triangle count, not {target_triangles!r}"
                    )
                target_triangles = t
            for key in ("levels", "max_error", "measure", "polish", "fix_worst"):
                if key in options:
                    raise LodgenError(
                        f"{key}= chooses or measures levels; a ProgressiveMesh keeps every "
                        "split (lodgen.simplify takes it)"
                    )
            _native = _lodgen.progressive(v, f, _argv(options, arrays=True), target_triangles)
        self._pm = _native

    def __len__(self) -> int:
        """Number of vertex splits."""
        return len(self._pm)

    def __repr__(self) -> str:
        counts = self.triangle_counts
        return (
            f"<lodgen.ProgressiveMesh {len(self)} splits, {counts[0]} -> "
            f"{counts[-1]} triangles, cursor at {self.applied}>"
        )

    @property
    def applied(self) -> int:
        """Splits applied at the cursor (0 = the base mesh)."""
        return self._pm.applied

    @property
    def triangle_counts(self) -> np.ndarray:
        """Triangle count after k splits, for k = 0 ... len(self)."""
        return self._pm.triangle_counts()

    def mesh_at(self, triangles: int) -> Tuple[np.ndarray, np.ndarray]:
        """The finest mesh of the sequence with at most ``triangles``
        triangles (the base mesh if it has more): (vertices, faces)."""
        k = self._pm.splits_for_triangles(_count(triangles, "triangles"))
        return self._back(self._pm.mesh_at_splits(k))

    def mesh_at_splits(self, k: int) -> Tuple[np.ndarray, np.ndarray]:
        """The mesh after ``k`` splits (clamped to ``[0, len(self)]``)."""
        return self._back(self._pm.mesh_at_splits(_count(k, "k")))

    @property
    def mesh(self) -> Tuple[np.ndarray, np.ndarray]:
        """The mesh at the cursor: (vertices, faces)."""
        return self._back(self._pm.mesh())

    @property
    def offset(self) -> Optional[np.ndarray]:
        """Where the mesh was computed from, far from the origin (:data:`FAR_COORDINATE`):
        the meshes this returns are moved back (float64), but the positions in
        :attr:`splits` are relative to it. None near the origin."""
        return None if self._offset is None else self._offset.copy()

    def _back(self, mesh: Tuple[np.ndarray, np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
        v, f = mesh
        return (v if self._offset is None else _moved_back(v, self._offset, np.float64)), f

    def refine(self, n: int = 1) -> int:
        """Apply up to ``n`` more splits at the cursor (none for ``n <= 0``);
        returns how many."""
        return self._pm.refine(_count(n, "n"))

    def coarsen(self, n: int = 1) -> int:
        """Undo up to ``n`` splits at the cursor (none for ``n <= 0``);
        returns how many."""
        return self._pm.coarsen(_count(n, "n"))

    def seek(self, k: int) -> None:
        """Move the cursor to exactly ``k`` splits (clamped to ``[0, len(self)]``)."""
        self._pm.seek(_count(k, "k"))

    @property
    def splits(self) -> np.ndarray:
        """Every vertex split, coarse to fine, as a structured array of
        :data:`SPLIT_DTYPE`; with :attr:`split_faces` and
        :attr:`split_corners` they replay the base mesh to the full one."""
        return self._split_arrays()[0]

    @property
    def split_faces(self) -> np.ndarray:
        """The triangles every split restores, split after split: an
        ``(F, 3)`` uint32 array (``splits["first_face"]`` indexes it)."""
        return self._split_arrays()[1]

    @property
    def split_corners(self) -> np.ndarray:
        """The corners every split moves from ``v1`` back to ``v0``, split
        after split: a ``(C, 2)`` uint32 array of (triangle, slot)
        (``splits["first_corner"]`` indexes it)."""
        return self._split_arrays()[2]

    def _split_arrays(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        v1, v0, p1, pm, p0, faces, corners, nf, nc, err = self._pm.split_columns()
        out = np.zeros(len(v1), dtype=SPLIT_DTYPE)
        out["v1"], out["v0"] = v1, v0
        out["p1"] = p1.reshape(-1, 3)
        out["p_merged"] = pm.reshape(-1, 3)
        out["p0"] = p0.reshape(-1, 3)
        out["n_faces"], out["n_corners"], out["error"] = nf, nc, err
        out["first_face"] = np.cumsum(nf, dtype=np.uint64) - nf
        out["first_corner"] = np.cumsum(nc, dtype=np.uint64) - nc
        return out, faces.reshape(-1, 3), corners.reshape(-1, 2)

    def full_in_input_order(self) -> Tuple[np.ndarray, np.ndarray]:
        """The fully refined mesh in the welded input's own numbering:
        equal, index for index, to the mesh that was simplified."""
        return self._back(self._pm.full_in_input_order())

    @property
    def vertex_origin(self) -> np.ndarray:
        """Progressive vertex -> welded input vertex."""
        return self._pm.vertex_origin

    @property
    def triangle_origin(self) -> np.ndarray:
        """Progressive triangle -> welded input triangle."""
        return self._pm.triangle_origin

    @property
    def vertex_map(self) -> np.ndarray:
        """Input vertex -> welded vertex (2**32 - 1 when unused)."""
        return self._pm.vertex_map

    @property
    def triangle_map(self) -> np.ndarray:
        """Welded triangle -> input triangle."""
        return self._pm.triangle_map


@dataclass(frozen=True)
class SimplifyResult:
    """What :func:`simplify` returns: the levels (finest first), the
    progressive mesh they were cut from, a note when the simplification
    stopped before the coarsest level (empty otherwise), and whether the
    levels' errors were measured (``measure=False`` skips it: each level's
    ``hausdorff`` is then the simplifier's quadric estimate, mean and RMS
    are NaN)."""

    levels: List[Level]
    progressive: ProgressiveMesh
    note: str
    measured: bool = True


def simplify(
    vertices: Any,
    faces: Any = None,
    levels: Union[Sequence[Union[float, int, str]], str] = _DEFAULT_LEVELS,
    **options: Any,
) -> SimplifyResult:
    """Build levels of detail of one mesh in one simplification pass and
    measure each against the input.

    ``vertices``: (n, 3) float32/float64 (computed in float32), ``faces``:
    (m, 3) integers; or a ``trimesh.Trimesh`` / ``(vertices, faces)`` as the
    first argument. ``levels``: ratios of the input's triangles (floats in
    (0, 1], or ``"50%"``) or triangle counts (ints); ``max_error=[0.1, 0.5]``
    builds levels by measured error (% of the bounding-box diagonal)
    instead. Other options are the command's flags (``tau``, ``boundary``,
    ``placement``, ``schedule``, ``method``, ``samples``, ...); ``reach``
    (on by default: the tips of thin parts kept) takes a factor, or
    ``reach=False`` (or ``None``, as in Rust) to turn it off;
    ``polish=True`` moves each returned level's vertices towards the input
    (lower error, same triangles; the progressive mesh keeps the
    simplifier's positions); ``fix_worst=True`` (or a round count,
    ``fix_worst=2``) fixes each level's worst spot where it lies (lower
    Hausdorff distance, same triangles; each round measures the level
    again, so it costs time; needs the measurement); a level the topology would stop above its
    count is reached by running again with joins and flattening allowed
    (holes close, sheets join), ``keep_topology=True`` stops above it
    instead, ``allow_topology_change=True`` also lets hard edges, seams and
    faces go (``result.note`` says when a level stopped above its count).

    Levels come finest first (as the command writes them), whatever the
    order asked. Each level's vertices have the input's float dtype, faces
    are int64. Each level's error is measured against the input (both
    directions, exact distances), which is about half the call's time on
    the bunny; ``measure=False`` skips it (same levels, the simplifier's
    estimate as ``errors.hausdorff``, ``result.measured`` false).
    """
    offset = _offset_of(vertices, faces)
    v, f, dtype = _moved_arrays(vertices, faces, offset)
    if "max_error" not in options:
        options = {"levels": levels, **options}
    elif levels is not _DEFAULT_LEVELS:
        raise LodgenError("levels= and max_error= cannot be used together")
    out, pm, note, measured = _lodgen.simplify(v, f, _argv(options, arrays=True))
    # (float64 in any byte order, or wider: float64; else float32)
    as_dtype = np.float64 if dtype.kind == "f" and dtype.itemsize >= 8 else np.float32
    result = [
        Level(_moved_back(lv, offset, as_dtype), lf.astype(np.int64), s, Errors._from(e))
        for lv, lf, e, s in out
    ]
    return SimplifyResult(result, ProgressiveMesh(_native=pm, _offset=offset), note, measured)


def measure(a: MeshLike, b: MeshLike, samples: float = 2.0) -> Errors:
    """Distance between two meshes (each a trimesh.Trimesh or a
    ``(vertices, faces)`` tuple), as ``lodgen measure A B``: one-sided and
    symmetric Hausdorff, mean and RMS; ``samples`` area samples per
    triangle of the larger mesh, plus every vertex."""
    # (both moved by A's offset when A is far from the origin)
    offset = _offset_of(a)
    av, af, _ = _moved_arrays(a, None, offset)
    bv, bf, _ = _moved_arrays(b, None, offset)
    return Errors._from(_lodgen.measure(av, af, bv, bf, float(samples)))


def build(
    path_in: Union[str, os.PathLike],
    path_out: Union[str, os.PathLike, None] = None,
    *,
    threads: Optional[int] = None,
    **cli_options: Any,
) -> dict:
    """``lodgen PATH_IN -o PATH_OUT **cli_options`` for one file (same
    bytes as the command), without printing. Returns the file's report (the
    command's ``--report`` JSON) as a dict. ``threads`` limits the file's
    own threads (default: every core). ``report="x.json"`` also writes it."""
    if threads is not None:
        if isinstance(threads, (bool, np.bool_)) or not isinstance(threads, (int, np.integer)):
            raise LodgenError(f"threads= must be a whole number of threads, not {threads!r}")
        if not 1 <= int(threads) <= _MAX_THREADS:
            raise LodgenError(f"threads= must be 1 to {_MAX_THREADS}, not {threads}")
        threads = int(threads)
    text = _lodgen.build(
        os.fspath(path_in),
        None if path_out is None else os.fspath(path_out),
        _argv(cli_options),
        threads,
    )
    return json.loads(text)


def read(path: Union[str, os.PathLike]) -> Tuple[np.ndarray, np.ndarray]:
    """Read a mesh file (.obj, .ply, .smf, .gltf, .glb) with lodgen's readers:
    every mesh its scene draws merged into (vertices float32 (n, 3), faces
    int64 (m, 3)), node transforms not applied (as ``lodgen measure``)."""
    v, f = _lodgen.read(os.fspath(path))
    return v, f.astype(np.int64)


def expand_inputs(
    inputs: Iterable[Union[str, os.PathLike]], out_dir: Union[str, os.PathLike]
) -> List[Tuple[str, str]]:
    """Batch mode's inputs (files, directories walked recursively, glob
    patterns) as (input, output) pairs, outputs under ``out_dir`` in the
    command's relative layout."""
    pairs = _lodgen.expand([os.fspath(i) for i in inputs], os.fspath(out_dir))
    return [(str(i), os.path.join(os.fspath(out_dir), str(r))) for i, r in pairs]


def batch(
    inputs: Iterable[Union[str, os.PathLike]],
    out_dir: Union[str, os.PathLike],
    **cli_options: Any,
) -> dict:
    """``lodgen INPUTS... --out-dir OUT_DIR **cli_options`` (``jobs``,
    ``force``, ...) without printing. Returns the batch report (every
    file's status, error, time and report); failed files are in it, not
    raised."""
    text = _lodgen.batch(
        [os.fspath(i) for i in inputs], os.fspath(out_dir), _argv(cli_options)
    )
    return json.loads(text)
