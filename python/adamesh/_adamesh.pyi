"""Type stubs of the compiled core (python/src/module.cpp). Use the `adamesh` package."""
from typing import Any, Callable, Optional, Sequence, Tuple

import numpy as np

class Error(Exception): ...
class UsageError(Error, ValueError): ...
class InputError(Error, ValueError): ...
class UnsupportedError(Error, ValueError): ...
class OutputError(Error, OSError): ...
class InternalError(Error, RuntimeError): ...
class CancelledError(Error): ...

class InputOptions:
    dims: Optional[Tuple[int, int, int]]
    type: Optional[str]
    spacing: Tuple[float, float, float]
    origin: Tuple[float, float, float]
    big_endian: bool
    header_bytes: int
    bounds: Optional[Tuple[float, float, float, float, float, float]]
    resolution: int
    nan_value: Optional[float]
    flip_inside: bool
    label: Optional[int]
    def __init__(self) -> None: ...

class Budget:
    none: Budget
    automatic: Budget
    levels: Budget
    max_error: Budget
    triangles: Budget

class LengthUnit:
    world: LengthUnit
    voxels: LengthUnit

class ExtractOptions:
    iso: Optional[float]
    budget: Budget
    levels: int
    max_error: float
    triangles: int
    r_max: float
    r_min: float
    unit: LengthUnit
    min_component: int
    validate: bool
    min_cavity: int
    improve: bool
    measure_levels: bool
    threads: int
    def __init__(self) -> None: ...

class _Volume:
    samples: np.ndarray
    dims: Tuple[int, int, int]
    spacing: Tuple[float, float, float]
    origin: Tuple[float, float, float]
    direction: Tuple[float, ...]
    inside_sign: float
    default_iso: Optional[float]
    format: str
    name: str
    borrowed: bool
    def stats(self) -> dict: ...

class _Mesh:
    vertices: np.ndarray
    faces: np.ndarray
    num_vertices: int
    num_triangles: int
    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None: ...
    def save(self, path: str, ascii: bool) -> None: ...

class _Hierarchy:
    num_splits: int
    num_vertices: int
    num_base_triangles: int
    iso: float
    voxel: float
    def cut(self, triangles: Optional[int] = ..., level: Optional[int] = ...,
            max_error: Optional[float] = ..., splits: Optional[int] = ...) -> _Mesh: ...
    def save(self, path: str) -> None: ...

def _volume_from_array(array: np.ndarray, spacing: Sequence[float], origin: Sequence[float],
                       direction: Sequence[float], inside_sign: float,
                       default_iso: Optional[float], name: str,
                       nan_value: Optional[float]) -> _Volume: ...
def _load(spec: str, options: InputOptions) -> _Volume: ...
def _read_mesh(path: str) -> _Mesh: ...
def _read_hierarchy(path: str, allow_partial: bool) -> _Hierarchy: ...
def _extract(source: Any, options: ExtractOptions, input: InputOptions,
             progress: Optional[Callable[[str, float], None]]
             ) -> Tuple[_Mesh, dict, Optional[_Hierarchy], str]: ...
def _mc(source: Any, iso: Optional[float], input: InputOptions, threads: int) -> _Mesh: ...
def _stats(mesh: _Mesh, field: Any, iso: Optional[float], reference: Optional[_Mesh],
           samples: int, input: InputOptions, threads: int) -> str: ...
def _shape_names() -> list: ...
