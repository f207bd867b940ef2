"""adamesh: adaptive multiresolution triangle meshes of iso-surfaces of volumes.

The pipeline of ``adamesh extract`` (surfels -> graph -> covering -> base mesh M0 -> 4-8
refinement hierarchy) as Python calls on numpy arrays and volume files::

    import numpy as np, adamesh
    z, y, x = np.mgrid[-1:1:64j, -1:1:64j, -1:1:64j]
    sdf = np.sqrt(x**2 + y**2 + z**2) - 0.8            # negative inside
    vol = adamesh.Volume(sdf, order="zyx", spacing=(2/63,) * 3, inside="negative")
    res = adamesh.extract(vol, triangles=5000)          # iso 0: the default for inside="negative"
    res.vertices, res.faces                             # (n, 3) float64 world units, (m, 3) int32
    res.hierarchy.cut(triangles=1000).save("coarse.ply")

Every call releases the GIL while it works. Errors are raised as adamesh.Error subclasses
(UsageError, InputError, UnsupportedError: ValueError; OutputError: OSError) carrying the same
one-line messages as the command line. See docs/PYTHON.md.
"""

from __future__ import annotations

import json
import math
import os
import sys
import warnings
from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence, Union

import numpy as np

from . import _adamesh
from ._adamesh import (  # noqa: F401  (re-exported)
    CancelledError,
    Error,
    InputError,
    InternalError,
    OutputError,
    UnsupportedError,
    UsageError,
)

__all__ = [
    "Volume", "Mesh", "Hierarchy", "Result", "load", "extract", "mc", "stats", "read_mesh",
    "load_hierarchy", "shape_names", "Error", "UsageError", "InputError", "UnsupportedError",
    "OutputError", "InternalError", "CancelledError", "AdameshWarning",
]

__version__ = "0.1.0"

PathLike = Union[str, "os.PathLike[str]"]


class AdameshWarning(UserWarning):
    """What ``adamesh extract`` prints as ``adamesh: warning: ...`` (a budget out of reach, a
    budget met below the decimation's shape floor, an iso-value on a label map): issued by
    :func:`extract` once per line, also in ``result.report["warnings"]``."""

# numpy sample types the library reads as they are (native byte order); everything else is
# converted: bool -> uint8, float16 -> float32, 64-bit integers -> float64 (exact up to 2**53).
_NATIVE = {np.dtype(t) for t in ("u1", "i1", "u2", "i2", "u4", "i4", "f4", "f8")}


def _sample_dtype(dtype: np.dtype, name: str) -> np.dtype:
    base = dtype.newbyteorder("=")
    if base in _NATIVE:
        return base
    if base.kind == "b":
        return np.dtype("u1")
    if base.kind == "f" and base.itemsize < 4:
        return np.dtype("f4")
    if base.kind in "iu" or base.kind == "f":
        return np.dtype("f8")
    raise UsageError(f"{name}: unsupported sample type {dtype} (integers, floats or bool)")


def _triple(value: Any, what: str, name: str, positive: bool = False) -> tuple:
    try:
        t = tuple(float(v) for v in value)
    except TypeError:
        t = (float(value),) * 3
    if len(t) != 3 or not all(np.isfinite(t)):
        raise UsageError(f"{name}: {what} expects 3 finite numbers, got {value!r}")
    if positive and not all(v > 0 for v in t):
        raise UsageError(f"{name}: {what} must be > 0, got {value!r}")
    return t


def _check_order(order: str, name: str) -> str:
    if order not in ("zyx", "xyz"):
        raise UsageError(
            f"{name}: order must be 'zyx' (numpy's C order: array[z, y, x]) or 'xyz' "
            f"(array[x, y, z]), got {order!r}")
    return order


class Volume:
    """A regular grid of samples placed in world space, from a numpy array or a file.

    ``Volume(array, order=..., spacing=1, origin=0, direction=identity, inside="positive")``

    * ``order`` (required): how the array's axes map to x, y, z. ``"zyx"`` means ``array[z, y, x]``
      (numpy's C order, scikit-image's (plane, row, column)); ``"xyz"`` means ``array[x, y, z]``
      (nibabel). Anything else is an error: a wrong order would silently transpose the object.
    * ``spacing``: voxel size along each *array axis*, in the order given by ``order`` (as
      scikit-image's ``marching_cubes(spacing=)``); a scalar for isotropic voxels.
    * ``origin``: world position (x, y, z) of ``array[0, 0, 0]``.
    * ``direction``: 3x3 matrix whose column ``a`` is the world direction of array axis ``a``
      (``order`` again); default: the x axis along world x, y along y, z along z.
    * ``inside``: ``"positive"`` (bright is inside, scans) or ``"negative"`` (signed distance
      fields: negative inside; the default iso-value is then 0).
    * any integer, float or bool dtype; any strides. The samples are shared with ``array`` when
      they are already x-fastest contiguous in a supported native type (``order="zyx"`` with a
      C-contiguous array, ``order="xyz"`` with a Fortran-contiguous one), copied otherwise.
    * ``nan_value``: replace NaN/Inf samples by this value (on a copy); otherwise they are an
      error, as on the command line.

    Vertices of meshes extracted from a volume are always world (x, y, z) coordinates.
    """

    def __init__(self, array: Any, *, order: str, spacing: Any = 1.0, origin: Any = (0, 0, 0),
                 direction: Any = None, inside: str = "positive", name: str = "<array>",
                 nan_value: Optional[float] = None) -> None:
        _check_order(order, name)
        a = np.asarray(array)
        if a.ndim != 3:
            raise UsageError(f"{name}: expected a 3-D array, got shape {a.shape}")
        if min(a.shape) < 1:
            raise UsageError(f"{name}: empty array, shape {a.shape}")
        if inside not in ("positive", "negative"):
            raise UsageError(f"{name}: inside must be 'positive' or 'negative', got {inside!r}")
        sp = _triple(spacing, "spacing", name, positive=True)
        org = _triple(origin, "origin", name)
        d = np.eye(3) if direction is None else np.asarray(direction, dtype=np.float64)
        if d.shape != (3, 3) or not np.all(np.isfinite(d)) or abs(np.linalg.det(d)) < 1e-12:
            raise UsageError(f"{name}: direction must be an invertible 3x3 matrix")
        zyx = a if order == "zyx" else a.transpose(2, 1, 0)
        if order == "zyx":  # per-axis values given in array order: reverse to x, y, z
            sp = sp[::-1]
            if direction is not None:
                d = d[:, ::-1]
        samples = np.ascontiguousarray(zyx, dtype=_sample_dtype(a.dtype, name))
        self._v = _adamesh._volume_from_array(
            samples, sp, org, tuple(np.ascontiguousarray(d).ravel()),
            -1.0 if inside == "negative" else 1.0, 0.0 if inside == "negative" else None,
            name, nan_value)
        self._order = order
        self._shares = bool(np.may_share_memory(samples, a))  # a view of the caller's array

    @classmethod
    def _wrap(cls, v: Any) -> "Volume":
        self = cls.__new__(cls)
        self._v = v
        self._order = "zyx"
        self._shares = False
        return self

    @property
    def order(self) -> str:
        """Axis order of ``array``, ``spacing`` and the columns of ``direction``."""
        return self._order

    @property
    def array(self) -> np.ndarray:
        """The samples as a read-only numpy view (no copy), axes in ``order``."""
        s = self._v.samples
        return s if self._order == "zyx" else s.transpose(2, 1, 0)

    @property
    def shape(self) -> tuple:
        return self.array.shape

    @property
    def dtype(self) -> np.dtype:
        return self._v.samples.dtype

    @property
    def spacing(self) -> tuple:
        s = tuple(self._v.spacing)
        return s[::-1] if self._order == "zyx" else s

    @property
    def origin(self) -> tuple:
        """World position (x, y, z) of sample [0, 0, 0]."""
        return tuple(self._v.origin)

    @property
    def direction(self) -> np.ndarray:
        d = np.array(self._v.direction, dtype=np.float64).reshape(3, 3)
        return d[:, ::-1].copy() if self._order == "zyx" else d

    @property
    def inside(self) -> str:
        return "negative" if self._v.inside_sign < 0 else "positive"

    @property
    def default_iso(self) -> Optional[float]:
        return self._v.default_iso

    @property
    def format(self) -> str:
        return self._v.format

    @property
    def name(self) -> str:
        return self._v.name

    @property
    def shares_memory(self) -> bool:
        """True when the samples are the caller's numpy array (no copy was made)."""
        return self._shares

    def stats(self) -> dict:
        """Value statistics: samples, min, max, mean, percentiles, otsu (a suggested iso-value)."""
        return self._v.stats()

    def __repr__(self) -> str:
        return (f"adamesh.Volume({self.name!r}, shape={self.shape}, order={self.order!r}, "
                f"dtype={self.dtype}, spacing={self.spacing}, inside={self.inside!r})")


def _input_options(res: Optional[int] = None, bounds: Optional[Sequence[float]] = None,
                   flip: bool = False, nan_value: Optional[float] = None,
                   dims: Optional[Sequence[int]] = None, type: Optional[str] = None,
                   spacing: Optional[Sequence[float]] = None,
                   origin: Optional[Sequence[float]] = None, big_endian: bool = False,
                   header_bytes: int = 0,
                   label: Union[int, str, Sequence[int], None] = None) -> Any:
    o = _adamesh.InputOptions()
    if res is not None:
        if not 2 <= int(res) <= 4096:
            raise UsageError(f"res must be between 2 and 4096, got {res}")
        o.resolution = int(res)
    if bounds is not None:
        o.bounds = tuple(float(b) for b in bounds)
    o.flip_inside = bool(flip)
    if nan_value is not None:
        o.nan_value = float(nan_value)
    if dims is not None:
        o.dims = tuple(int(d) for d in dims)
    if type is not None:
        o.type = str(type)
    if spacing is not None:
        o.spacing = tuple(float(s) for s in spacing)
    if origin is not None:
        o.origin = tuple(float(s) for s in origin)
    if label is not None:
        if isinstance(label, str):
            o.label = label
        elif isinstance(label, (int, np.integer)):
            o.label = str(int(label))
        else:
            o.label = ",".join(str(int(x)) for x in label)
    o.big_endian = bool(big_endian)
    o.header_bytes = int(header_bytes)
    return o


def load(path: PathLike, **input_options: Any) -> Volume:
    """Reads a volume file (NRRD, MetaImage, NIfTI, VTK, VTI, SLC, MRC, raw) or samples
    ``shape:NAME`` / ``expr:'EXPR'``. Keywords: ``res``, ``bounds`` (implicit inputs),
    ``nan_value``, ``flip``, ``label`` (label maps: the 0/1 mask of one label, or of a set —
    ``"1-15"``, ``"1,3,5-9"`` or a list of values — whose union is one surface; iso 0.5); raw files: ``dims`` (x, y, z), ``type``, ``spacing``, ``origin``,
    ``big_endian``, ``header_bytes``. The result's ``order`` is ``"zyx"``."""
    return Volume._wrap(_adamesh._load(os.fspath(path), _input_options(**input_options)))


class Mesh:
    """A triangle mesh: ``vertices`` (n, 3) float64 world coordinates, ``faces`` (m, 3) int32,
    counter-clockwise seen from outside."""

    def __init__(self, vertices: Any = None, faces: Any = None, *, _mesh: Any = None) -> None:
        if _mesh is None:
            v = np.zeros((0, 3)) if vertices is None else np.asarray(vertices)
            f = np.zeros((0, 3), dtype=np.int64) if faces is None else np.asarray(faces)
            _mesh = _adamesh._Mesh(v, f)
        self._m = _mesh
        self._vertices: Optional[np.ndarray] = None
        self._faces: Optional[np.ndarray] = None

    @property
    def vertices(self) -> np.ndarray:
        if self._vertices is None:
            self._vertices = self._m.vertices
            self._vertices.flags.writeable = False
        return self._vertices

    @property
    def faces(self) -> np.ndarray:
        if self._faces is None:
            self._faces = self._m.faces
            self._faces.flags.writeable = False
        return self._faces

    def __len__(self) -> int:
        return self._m.num_triangles

    def save(self, path: PathLike, *, ascii: bool = False) -> None:
        """Writes the mesh; the format comes from the extension (.ply .obj .off .stl, and any
        other format the library writes). Atomic: no half-written file on error."""
        self._m.save(os.fspath(path), bool(ascii))

    def __repr__(self) -> str:
        return f"adamesh.Mesh({self._m.num_vertices} vertices, {self._m.num_triangles} triangles)"


def read_mesh(path: PathLike) -> Mesh:
    """Reads a PLY, OBJ, OFF or STL mesh."""
    return Mesh(_mesh=_adamesh._read_mesh(os.fspath(path)))


class Hierarchy:
    """The base mesh plus the 4-8 splits in progressive order (docs/HIERARCHY.md): meshes are cut
    from it without the volume, and it is stored as an ``.amh`` file."""

    def __init__(self, _h: Any) -> None:
        self._h = _h

    def cut(self, *, triangles: Optional[int] = None, level: Optional[int] = None,
            max_error: Optional[float] = None, splits: Optional[int] = None,
            fit: bool = False) -> Mesh:
        """One of: ``triangles`` (the largest prefix with at most that many), ``level`` (uniform
        level M_level), ``max_error`` (every triangle within that distance, world units),
        ``splits`` (the first N splits). ``fit``: least-squares vertex offsets against the
        hierarchy's finest mesh, without the volume (``adamesh level --fit-finest``)."""
        return Mesh(_mesh=self._h.cut(triangles=triangles, level=level, max_error=max_error,
                                      splits=splits, fit=bool(fit)))

    def save(self, path: PathLike) -> None:
        """Writes the ``.amh`` file (the bytes ``adamesh extract --hierarchy`` writes)."""
        self._h.save(os.fspath(path))

    @staticmethod
    def load(path: PathLike, *, allow_partial: bool = False) -> "Hierarchy":
        return Hierarchy(_adamesh._read_hierarchy(os.fspath(path), bool(allow_partial)))

    @property
    def num_splits(self) -> int:
        return self._h.num_splits

    @property
    def num_vertices(self) -> int:
        return self._h.num_vertices

    @property
    def num_base_triangles(self) -> int:
        return self._h.num_base_triangles

    @property
    def iso(self) -> float:
        return self._h.iso

    @property
    def voxel(self) -> float:
        return self._h.voxel

    def __repr__(self) -> str:
        return (f"adamesh.Hierarchy({self.num_base_triangles} base triangles, "
                f"{self.num_splits} splits)")


def load_hierarchy(path: PathLike, *, allow_partial: bool = False) -> Hierarchy:
    return Hierarchy.load(path, allow_partial=allow_partial)


@dataclass
class Base:
    """The base mesh M0 with its per-vertex flags."""
    mesh: Mesh
    border: np.ndarray     # uint8 per vertex: 1 on the volume border
    component: np.ndarray  # uint32 per vertex: connected component of the surface


@dataclass
class Result:
    """What :func:`extract` returns."""
    mesh: Mesh                       # the refined mesh (the base mesh when base_only=True)
    base: Base
    hierarchy: Optional[Hierarchy]   # None when base_only=True
    report: dict = field(repr=False)  # the `adamesh extract --report` JSON as a dict

    @property
    def vertices(self) -> np.ndarray:
        return self.mesh.vertices

    @property
    def faces(self) -> np.ndarray:
        return self.mesh.faces


def _progress_callback(progress: Any) -> Optional[Callable[[str, float], None]]:
    """None/False: silent. A callable: called as progress(stage, fraction). True: a tqdm bar per
    stage when tqdm is installed, else one line per stage on stderr."""
    if progress is None or progress is False:
        return None
    if callable(progress):
        return progress
    try:
        from tqdm import tqdm  # optional
    except ImportError:
        tqdm = None
    state: dict = {"stage": None, "bar": None}

    def report(stage: str, fraction: float) -> None:
        if stage != state["stage"]:
            if state["bar"] is not None:
                state["bar"].close()
            state["stage"] = stage
            if tqdm is not None:
                state["bar"] = tqdm(total=100, desc=f"adamesh {stage}", leave=False)
            else:
                print(f"adamesh: {stage}", file=sys.stderr)
        bar = state["bar"]
        if bar is not None:
            bar.update(max(0, int(fraction * 100) - bar.n))
            if fraction >= 1:
                bar.close()
                state["bar"] = None
    return report


def _source(source: Any) -> Any:
    if isinstance(source, Volume):
        return source._v
    if isinstance(source, np.ndarray):
        raise UsageError("extract: wrap numpy arrays in adamesh.Volume(array, order=..., "
                         "spacing=...) so that the axis order is explicit")
    return os.fspath(source)


def extract(source: Union[Volume, PathLike], iso: Optional[float] = None, *,
            triangles: Optional[int] = None, max_error: Optional[float] = None,
            levels: Optional[int] = None, base_only: bool = False,
            rmax: Optional[float] = None, rmin: Optional[float] = None, voxels: bool = False,
            min_component: int = 0, min_cavity: int = 0, max_handle: float = 0,
            improve: bool = True, fit: str = "auto", validate: bool = False,
            measure: bool = False, threads: int = 0, progress: Any = None,
            **input_options: Any) -> Result:
    """Adaptive mesh of the iso-surface ``iso`` of ``source`` (a Volume, a volume file,
    ``shape:NAME`` or ``expr:'EXPR'``): what ``adamesh extract`` computes, byte for byte.

    Budget (at most one): ``triangles`` (the N-triangle mesh), ``max_error`` (world units),
    ``levels`` (uniform M_levels); default: every triangle within 0.25 voxel, at most marching
    cubes' triangle count. ``base_only=True``: the base mesh M0 alone, no hierarchy.
    ``rmax``/``rmin`` disk radii (world units, voxels with ``voxels=True``), ``min_component``
    (drop smaller components, surfels), ``min_cavity`` (fill enclosed pockets of outside under
    that many voxels), ``max_handle`` (cut handles and plug tunnels whose shortest loop is under
    that many voxels), ``improve`` (shape improvement, --no-improve), ``fit`` ("auto": "l2" for
    adaptive meshes, "surface" for levels and without improvement; "l2": least-squares vertex
    offsets, lower RMS distance; "surface": vertices on the iso-surface),
    ``validate`` (covering validator), ``measure`` (per-level error figures in the report),
    ``threads`` (0 = all cores), ``progress`` (callable(stage, fraction), or True for tqdm).
    File and shape inputs take the keywords of :func:`load`.
    """
    budgets = sum(v is not None for v in (triangles, max_error, levels))
    if budgets > 1:
        raise UsageError("extract: give at most one of triangles=, max_error=, levels=")
    if base_only and budgets:
        raise UsageError("extract: base_only=True takes no budget")
    o = _adamesh.ExtractOptions()
    if iso is not None:
        o.iso = float(iso)
    if base_only:
        o.budget = _adamesh.Budget.none
    elif triangles is not None:
        o.budget, o.triangles = _adamesh.Budget.triangles, _count(triangles, "triangles", 1)
    elif max_error is not None:
        o.budget, o.max_error = _adamesh.Budget.max_error, float(max_error)
    elif levels is not None:
        o.budget, o.levels = _adamesh.Budget.levels, _count(levels, "levels", 0)
    if rmax is not None:
        o.r_max = float(rmax)
    if rmin is not None:
        o.r_min = float(rmin)
    o.unit = _adamesh.LengthUnit.voxels if voxels else _adamesh.LengthUnit.world
    o.min_component = _count(min_component, "min_component", 0)
    o.min_cavity = _count(min_cavity, "min_cavity", 0)
    if not (isinstance(max_handle, (int, float)) and math.isfinite(max_handle) and max_handle >= 0):
        raise UsageError(f"extract: max_handle must be a length >= 0 (voxels), not {max_handle!r}")
    o.max_handle = float(max_handle)
    o.improve = bool(improve)
    o.fit = str(fit)
    o.validate = bool(validate)
    o.measure_levels = bool(measure)
    o.threads = _count(threads, "threads", 0)
    src = _source(source)
    if isinstance(source, Volume) and input_options:
        raise UsageError(f"extract: {sorted(input_options)} apply to files and shapes, "
                         "not to a Volume")
    mesh, base, hierarchy, report = _adamesh._extract(
        src, o, _input_options(**input_options), _progress_callback(progress))
    base_mesh = Mesh(_mesh=base["mesh"])
    out_mesh = Mesh(_mesh=mesh) if hierarchy is not None else base_mesh
    rep = json.loads(report)
    for w in rep.get("warnings", []):
        warnings.warn(w, AdameshWarning, stacklevel=2)
    return Result(mesh=out_mesh, base=Base(base_mesh, base["border"], base["component"]),
                  hierarchy=None if hierarchy is None else Hierarchy(hierarchy),
                  report=rep)


def _count(value: Any, what: str, minimum: int) -> int:
    if isinstance(value, bool) or int(value) != value or value < minimum:
        raise UsageError(f"extract: {what} must be an integer >= {minimum}, got {value!r}")
    return int(value)


def mc(source: Union[Volume, PathLike], iso: Optional[float] = None, *, threads: int = 0,
       **input_options: Any) -> Mesh:
    """Reference marching cubes mesh (``adamesh mc``): watertight where the surface is closed,
    2-manifold, consistently oriented."""
    return Mesh(_mesh=_adamesh._mc(_source(source), None if iso is None else float(iso),
                                   _input_options(**input_options), _count(threads, "threads", 0)))


def stats(mesh: Union[Mesh, PathLike], *, field: Union[Volume, PathLike, None] = None,
          iso: Optional[float] = None, reference: Union[Mesh, PathLike, None] = None,
          samples: int = 0, threads: int = 0, **input_options: Any) -> dict:
    """``adamesh stats --json`` as a dict: topology, quality, area, volume; with ``field`` the
    distance to its iso-surface (eps_e, eps_n); with ``reference`` Hausdorff distances."""
    if not isinstance(mesh, Mesh):
        mesh = read_mesh(mesh)
    if reference is not None and not isinstance(reference, Mesh):
        reference = read_mesh(reference)
    if iso is not None and field is None:
        raise UsageError("stats: iso= needs field=")
    f = None if field is None else _source(field)
    return json.loads(_adamesh._stats(mesh._m, f, None if iso is None else float(iso),
                                      None if reference is None else reference._m,
                                      _count(samples, "samples", 0),
                                      _input_options(**input_options),
                                      _count(threads, "threads", 0)))


def shape_names() -> list:
    """Names of the built-in shapes (``shape:NAME``)."""
    return list(_adamesh._shape_names())
