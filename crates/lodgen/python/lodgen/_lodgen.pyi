"""Type stubs of the native module lodgen._lodgen (crates/lodgen/src/python.rs).

Use the wrappers in ``lodgen`` instead: they convert arrays and keyword
options. Vertices are C-contiguous float32 (n, 3), faces int64 (m, 3);
``argv`` is the command line's flags.
"""

from typing import List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

class LodgenError(ValueError):
    """A mesh, option or file lodgen cannot use; the command line's message."""

_Arrays = Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]
# diagonal, hausdorff, mean, rms, a->b max, mean, rms, samples, b->a max, mean, rms, samples
_ErrorTuple = List[float]

class ProgressiveMesh:
    def __len__(self) -> int: ...
    @property
    def applied(self) -> int: ...
    def triangle_counts(self) -> npt.NDArray[np.uint64]: ...
    def splits_for_triangles(self, triangles: int) -> int: ...
    def mesh_at_splits(self, k: int) -> _Arrays: ...
    def full_in_input_order(self) -> _Arrays: ...
    def mesh(self) -> _Arrays: ...
    def refine(self, n: int) -> int: ...
    def coarsen(self, n: int) -> int: ...
    def seek(self, k: int) -> None: ...
    @property
    def vertex_origin(self) -> npt.NDArray[np.uint32]: ...
    @property
    def triangle_origin(self) -> npt.NDArray[np.uint32]: ...
    @property
    def vertex_map(self) -> npt.NDArray[np.uint32]: ...
    @property
    def triangle_map(self) -> npt.NDArray[np.uint32]: ...
    def split_columns(
        self,
    ) -> Tuple[
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.float32],
        npt.NDArray[np.float32],
        npt.NDArray[np.float32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.uint32],
        npt.NDArray[np.float32],
    ]: ...

def simplify(
    vertices: npt.NDArray[np.float32], faces: npt.NDArray[np.int64], argv: Sequence[str]
) -> Tuple[
    List[Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32], _ErrorTuple, int]],
    ProgressiveMesh,
    str,
    bool,
]: ...
def progressive(
    vertices: npt.NDArray[np.float32],
    faces: npt.NDArray[np.int64],
    argv: Sequence[str],
    target_triangles: Optional[int] = None,
) -> ProgressiveMesh: ...
def measure(
    av: npt.NDArray[np.float32],
    af: npt.NDArray[np.int64],
    bv: npt.NDArray[np.float32],
    bf: npt.NDArray[np.int64],
    samples: float,
) -> _ErrorTuple: ...
def build(
    input: str, output: Optional[str], argv: Sequence[str], threads: Optional[int] = None
) -> str: ...
def batch(inputs: Sequence[str], out_dir: str, argv: Sequence[str]) -> str: ...
def expand(inputs: Sequence[str], out_dir: str) -> List[Tuple[str, str]]: ...
def read(path: str) -> _Arrays: ...
