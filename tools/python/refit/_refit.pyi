# Type stubs of the extension refit._refit (tools/python/refit_python.cpp);
# tests/python/test_refit.py checks that they name what the module has.
from typing import Any, Callable, Optional, Sequence, overload

import numpy as np
import numpy.typing as npt

__version__: str

ArrayN3 = npt.NDArray[np.float64]
Progress = Optional[Callable[[str], None]]

class Error(RuntimeError):
    """Every error of refit; exit_code: the command line's exit code for the same failure."""
    exit_code: int

class InputError(Error):
    """Bad input (exit code 1): the message names the file (and line) and the problem."""

class UsageError(Error, ValueError):
    """An argument value the command line refuses as a usage error (exit code 2)."""

class ResourceError(Error, MemoryError):
    """Out of resources: memory (exit code 3)."""

class Garment:
    def __init__(
        self,
        positions: npt.ArrayLike,
        face_indices: npt.ArrayLike,
        face_sizes: npt.ArrayLike,
        line_indices: Optional[npt.ArrayLike] = None,
        line_sizes: Optional[npt.ArrayLike] = None,
    ) -> None: ...
    @property
    def positions(self) -> ArrayN3: ...
    @property
    def vertex_count(self) -> int: ...
    @property
    def face_count(self) -> int: ...

class Body:
    def __init__(self, vertices: npt.ArrayLike, triangles: npt.ArrayLike, name: str = "body") -> None: ...
    @property
    def vertices(self) -> ArrayN3: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def name(self) -> str: ...
    def with_vertices(self, vertices: npt.ArrayLike) -> Body: ...

class Features:
    def __len__(self) -> int: ...
    @property
    def names(self) -> list[str]: ...
    @property
    def path(self) -> str: ...
    @property
    def units(self) -> str: ...

class Result:
    @property
    def positions(self) -> ArrayN3: ...
    @property
    def warped(self) -> ArrayN3: ...
    @property
    def report(self) -> dict[str, Any]: ...
    @property
    def warnings(self) -> list[str]: ...

class Binding:
    def __init__(
        self,
        garment: Garment,
        body_a: Body,
        features: Optional[Features] = None,
        units: str = "cm",
        stage: str = "full",
        symmetry: str = "auto",
        collision: bool = True,
        clearance: float = 0.2,
        threads: int = 0,
        metrics: bool = False,
        progress: Progress = None,
    ) -> None: ...
    @overload
    def resize(self, body_b: Body, progress: Progress = None) -> Result: ...
    @overload
    def resize(self, vertices: npt.ArrayLike, progress: Progress = None) -> Result: ...
    @property
    def body_a(self) -> Body: ...

def read_garment(path: str, keep_text: bool = True) -> Garment: ...
def write_garment(garment: Garment, positions: npt.ArrayLike, path: str) -> None: ...
def read_body(path: str) -> Body: ...
def keep_freed_memory() -> bool: ...
def read_features(path: str, units: str = "cm") -> Features: ...
def compare(
    garment: Garment,
    result: npt.ArrayLike,
    body_a: Body,
    body_b: Body,
    features: Optional[Features] = None,
    fit_band: float = 1.0,
) -> dict[str, Any]: ...
def render(
    body: Body,
    garment: Garment,
    positions: Optional[npt.ArrayLike] = None,
    path: str = "",
    views: Sequence[str] = ("front",),
    width: int = 800,
    height: int = 1000,
    zoom: float = 1.0,
    centre: tuple[float, float] = (0.5, 0.5),
) -> npt.NDArray[np.uint8]: ...
