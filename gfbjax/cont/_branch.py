"""Continuation results: ``Branch`` (stacked numpy arrays) with npz + JSON storage and xarray / netCDF export.

File format (readable with plain numpy + json, no gfbjax needed)
---------------------------------------------------------------
``save(path)`` writes ``<path>.npz`` and ``<path>.json``; ``load(path)`` reads them back (``path`` may end in
``.npz``, ``.json`` or neither).

npz keys (P = number of points):

- ``lam`` (P,), ``period`` (P,) (NaN for equilibria), ``l2`` (P,) L2 norm
  sqrt(int_0^1 |x|^2 dt) of the cycle (|x| for equilibria),
- ``xmax``/``xmin`` (P, k): max/min over the cycle of the recorded components,
- ``multipliers`` (P, n) complex: Floquet multipliers sorted by decreasing
  modulus (eigenvalues of df/dx for equilibria, sorted by decreasing real part),
- ``stable`` (P,) bool, ``trivial_error`` (P,) |mu_trivial - 1| (NaN for equilibria),
- ``newton_iterations`` (P,) int, ``ds`` (P,) step length that produced the point,
- ``tangent_lam`` (P,) lam-component of the normalised tangent,
- optional ``state_<name>`` arrays (full states of every point: ``xm`` (P,N+1,n),
  ``xi`` (P,N,m-1,n), ``T``, ``lam``, ``mesh`` (N+1,) for cycles; ``x`` (P,n) for
  equilibria), and ``special<i>_<name>`` for the state of special point i.

JSON sidecar, one object:

- ``format`` = ``"gfbjax.cont.Branch"`` and ``version`` (:data:`FORMAT_VERSION`): what the file is, so that a
  foreign JSON file is recognised as such;
- ``kind`` ("cycles"|"equilibria"), ``points`` (P, so that an npz from another save is caught),
  ``components`` (recorded state indices, the k columns of ``xmax``/``xmin``), ``component_names`` (their names,
  k strings, or null), ``units`` ({npz key: unit text}, e.g. ``{"lam": "Omega_bar", "xmax": "over clearance c"}``;
  keys without an entry are in the problem's own units);
- ``outcome`` (why the branch ended, one of :class:`Outcome`) and ``message`` (a sentence with the details);
- ``special`` (the :class:`SpecialPoint` records: ``type`` in {"LPC","PD","NS","BPC","HOPF","FOLD","BP"},
  ``index`` (row in the arrays), ``lam``, ``period``, ``spectrum`` as [re, im] pairs, ``located``, ``residual``,
  ``angle`` (NS: arg mu in radians), ``omega`` (HOPF), ``state`` (i of the ``special<i>_*`` arrays),
  ``normal_form``);
- ``m`` (collocation degree, null for equilibria) and ``keys`` (the npz keys);
- ``accuracy_tol``: the largest accepted distance of the trivial multiplier from +1 (cycles; null otherwise);
  points above it are flagged (:attr:`Branch.flagged`);
- ``monitor``: null, or ``{"name", "minimum", "unit", "stop"}`` of the physical bound watched along the branch
  (:class:`~._problem.Monitor`), whose value at every point is the npz array ``monitor`` (P,); points at or
  below ``minimum`` are flagged;
- ``mesh_tol``: null, or the largest accepted a-posteriori mesh error of a cycle (:mod:`._mesh`), whose value at
  every point is the npz array ``mesh_error`` (P,); points above it are flagged;
- ``stiff_tol``: null, or the largest accepted modulus of the multipliers the mesh gives the fast modes (exactly
  about 0; :mod:`._resolution`), whose value at every point is the npz array ``stiff_modulus`` (P,); points
  above it are flagged; ``multiplier_tol``: likewise for the estimated error of the deciding multipliers, the
  array ``multiplier_error`` (P,); ``collocation``: the cycles' collocation points ("gauss" or "radau"; null for
  equilibria and for files written before it was recorded, which are Gauss);
- ``meta``: a JSON object the caller attached (:attr:`Branch.meta`).  The engine writes none of it; the bearing
  analyses (:mod:`gfbjax.analyses.cycles`) record there the system (SI spec with its conventions, dimensionless
  groups), the grid, the state layout and the rpm conversion.

Version history: 2 added ``format``, ``version``, ``points``, ``component_names``, ``units`` and ``meta``.  Files
without ``format`` are read as older versions: version 1 (``outcome``, typed special points) and version 0
(free-text ``reason``, special points with ``multipliers``), with empty ``meta``.

xarray / netCDF: :meth:`Branch.to_xarray` and :meth:`Branch.to_netcdf` (see there); the full states stay in the
npz only.

Errors: :meth:`Branch.load` raises :class:`BranchFileError` (a ``ValueError``), with a one-line message naming the
file and what is wrong, for a missing file, a truncated or corrupt npz, JSON that is not a branch sidecar, and
arrays that do not fit together.
"""
from __future__ import annotations

import json
import math
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._results import Outcome, SpecialPoint

__all__ = ["ARRAY_KEYS", "Branch", "BranchFileError", "FORMAT", "FORMAT_VERSION", "PointRecord"]

ARRAY_KEYS = ("lam", "period", "l2", "xmax", "xmin", "multipliers", "stable", "trivial_error",
              "newton_iterations", "ds", "tangent_lam")
_MATRIX_KEYS = ("xmax", "xmin", "multipliers")  # (P, k) or (P, n); the others are (P,)

#: The ``format`` value of a branch sidecar, and the newest version this module writes and reads.
FORMAT = "gfbjax.cont.Branch"
FORMAT_VERSION = 2

#: Branch kinds the engine produces.
KINDS = ("cycles", "equilibria")


class BranchFileError(ValueError):
    """A branch file that cannot be read: missing, truncated, corrupt, foreign, or with parts that do not fit
    together.  The message is one line that names the file and what is wrong."""


@dataclass
class PointRecord:
    lam: float
    period: float
    l2: float
    xmax: np.ndarray
    xmin: np.ndarray
    multipliers: np.ndarray
    stable: bool
    trivial_error: float
    newton_iterations: int
    ds: float
    tangent_lam: float
    state: dict[str, np.ndarray] | None = None
    monitor: float = math.nan
    mesh_error: float = math.nan
    stiff_modulus: float = math.nan
    multiplier_error: float = math.nan


@dataclass
class Branch:
    """A computed branch; every array has the point index as leading axis (shapes in the module docstring).

    Description of the results (written to the JSON sidecar, the xarray attributes and netCDF):
    ``component_names`` names the k recorded components (columns of ``xmax``/``xmin``; None: unnamed);
    ``units`` maps array names (``"lam"``, ``"period"``, ``"xmax"``, ...) to a unit text; ``meta`` is any
    JSON-able dict the caller attaches (the engine leaves it empty; NumPy scalars and arrays are written as
    numbers and lists).
    """

    kind: str
    components: list[int]
    lam: np.ndarray
    period: np.ndarray
    l2: np.ndarray
    xmax: np.ndarray
    xmin: np.ndarray
    multipliers: np.ndarray
    stable: np.ndarray
    trivial_error: np.ndarray
    newton_iterations: np.ndarray
    ds: np.ndarray
    tangent_lam: np.ndarray
    special: list[SpecialPoint] = field(default_factory=list)
    outcome: Outcome = Outcome.MAX_POINTS
    message: str = ""
    states: dict[str, np.ndarray] | None = None
    special_states: list[dict[str, np.ndarray]] = field(default_factory=list)
    m: int | None = None
    component_names: list[str] | None = None
    units: dict[str, str] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)
    accuracy_tol: float | None = None
    monitor: np.ndarray | None = None
    monitor_info: dict[str, Any] | None = None
    mesh_error: np.ndarray | None = None
    mesh_tol: float | None = None
    stiff_modulus: np.ndarray | None = None
    stiff_tol: float | None = None
    multiplier_error: np.ndarray | None = None
    multiplier_tol: float | None = None
    collocation: str | None = None

    def __len__(self) -> int:
        return len(self.lam)

    @property
    def flagged(self) -> np.ndarray:
        """(P,) bool: points whose trivial multiplier is farther than ``accuracy_tol`` from +1 (their multipliers
        are not accurate to that level, so their stability labels cannot be trusted: refine the mesh), and points
        whose monitored bound is violated (``monitor <= monitor_info["minimum"]``: outside the model's validity,
        e.g. a closed film), and cycles whose estimated mesh error exceeds ``mesh_tol`` (the orbit, its period and
        multipliers are not resolved to that level), and cycles whose fast modes get multipliers above
        ``stiff_tol`` while their exact value is about 0 (:mod:`._resolution`: a spurious multiplier in the band
        where stability and events are decided), and cycles whose deciding multipliers the mesh does not resolve
        to ``multiplier_tol``.  All False for a branch with none of these."""
        out = np.zeros(len(self), bool)
        if self.accuracy_tol is not None:
            err = np.asarray(self.trivial_error, float)
            out |= np.isfinite(err) & (err > self.accuracy_tol)
        if self.monitor is not None and self.monitor_info is not None:
            out |= np.asarray(self.monitor, float) <= float(self.monitor_info["minimum"])
        if self.mesh_error is not None and self.mesh_tol is not None:
            out |= np.asarray(self.mesh_error, float) > self.mesh_tol
        if self.stiff_modulus is not None and self.stiff_tol is not None:
            out |= np.asarray(self.stiff_modulus, float) > self.stiff_tol
        if self.multiplier_error is not None and self.multiplier_tol is not None:
            out |= np.asarray(self.multiplier_error, float) > self.multiplier_tol
        return out

    @classmethod
    def from_points(cls, kind: str, components: list[int], points: list[PointRecord],
                    special: list[SpecialPoint], special_states: list[dict[str, np.ndarray]],
                    outcome: Outcome, message: str = "", m: int | None = None,
                    shared_state: dict[str, np.ndarray] | None = None,
                    accuracy_tol: float | None = None, monitor_info: dict[str, Any] | None = None,
                    mesh_tol: float | None = None, stiff_tol: float | None = None,
                    multiplier_tol: float | None = None, collocation: str | None = None) -> "Branch":
        def stack(name, dtype=float, shape=(0,)):
            vals = [getattr(p, name) for p in points]
            return np.array(vals, dtype=dtype) if vals else np.zeros(shape, dtype)

        k = len(components)
        nmu = len(points[0].multipliers) if points else 0
        states = None
        if points and all(p.state is not None for p in points):
            states = {key: np.stack([p.state[key] for p in points]) for key in points[0].state}
            if shared_state:
                states.update(shared_state)
        # A Floquet method may compute more multipliers at some points (a Krylov method reaching inside the unit
        # circle):
        # the rows keep the first point's count, the largest in modulus (padded with NaN where fewer)
        mu = np.full((len(points), nmu), np.nan, complex)
        for i, p in enumerate(points):
            row = np.asarray(p.multipliers, complex)[:nmu]
            mu[i, :row.size] = row
        return cls(kind, list(components), stack("lam"), stack("period"), stack("l2"),
                   stack("xmax", shape=(0, k)), stack("xmin", shape=(0, k)),
                   mu, stack("stable", bool),
                   stack("trivial_error"), stack("newton_iterations", int), stack("ds"),
                   stack("tangent_lam"), list(special), Outcome(outcome), message, states, list(special_states), m,
                   accuracy_tol=accuracy_tol, monitor=None if monitor_info is None else stack("monitor"),
                   monitor_info=monitor_info, mesh_error=None if mesh_tol is None else stack("mesh_error"),
                   mesh_tol=mesh_tol, stiff_modulus=None if stiff_tol is None else stack("stiff_modulus"),
                   stiff_tol=stiff_tol,
                   multiplier_error=None if multiplier_tol is None else stack("multiplier_error"),
                   multiplier_tol=multiplier_tol, collocation=collocation)

    def special_of(self, kind: str) -> list[SpecialPoint]:
        return [s for s in self.special if s.type == kind]

    # ------------------------------------------------------------------ io
    def save(self, path: str | Path) -> tuple[Path, Path]:
        """Write ``<path>.npz`` and ``<path>.json`` (format in the module docstring); returns both paths.

        ValueError, before anything is written, when ``meta`` is not JSON-able or ``component_names``/``units``
        do not fit the branch."""
        npz, js = _paths(path)
        self._check_description()
        arrays = {key: getattr(self, key) for key in ARRAY_KEYS}
        if self.states is not None:
            arrays.update({f"state_{k}": v for k, v in self.states.items()})
        for i, st in enumerate(self.special_states):
            arrays.update({f"special{i}_{k}": v for k, v in st.items()})
        if self.monitor is not None:
            arrays["monitor"] = np.asarray(self.monitor, float)
        if self.mesh_error is not None:
            arrays["mesh_error"] = np.asarray(self.mesh_error, float)
        if self.stiff_modulus is not None:
            arrays["stiff_modulus"] = np.asarray(self.stiff_modulus, float)
        if self.multiplier_error is not None:
            arrays["multiplier_error"] = np.asarray(self.multiplier_error, float)
        head = {"format": FORMAT, "version": FORMAT_VERSION, "kind": self.kind, "points": len(self),
                "components": [int(c) for c in self.components],
                "component_names": None if self.component_names is None else list(self.component_names),
                "units": dict(self.units), "outcome": str(self.outcome), "message": self.message, "m": self.m,
                "special": [s.to_json() for s in self.special], "keys": sorted(arrays), "meta": self.meta,
                "accuracy_tol": self.accuracy_tol, "monitor": self.monitor_info, "mesh_tol": self.mesh_tol,
                "stiff_tol": self.stiff_tol, "multiplier_tol": self.multiplier_tol, "collocation": self.collocation}
        try:  # serialise before writing: a meta that is not JSON-able leaves no half-written pair behind
            text = json.dumps(head, indent=1, default=_json_default)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"Branch.meta cannot be written as JSON: {exc}") from None
        np.savez(npz, **arrays)
        js.write_text(text, encoding="utf-8")
        return npz, js

    @classmethod
    def load(cls, path: str | Path) -> "Branch":
        """Read a branch written by :meth:`save` (this or an older version of gfbjax).

        Raises :class:`BranchFileError` (one line: the file and what is wrong) for a missing ``.json`` or
        ``.npz``, a truncated or corrupt npz, JSON that is not a branch sidecar (another format, missing keys,
        wrong types) and arrays whose lengths or widths disagree with each other or with the JSON."""
        if Path(path).is_dir():
            raise BranchFileError(f"{path}: a folder, not a branch file (pass the branch in it, e.g. "
                                  f"{Path(path) / 'branch.npz'})")
        npz, js = _paths(path)
        if not npz.is_file() and not js.is_file():
            raise BranchFileError(f"{path}: no such branch file (neither {npz.name} nor {js.name} exists)")
        head = _read_head(js, npz)
        data = _read_npz(npz)
        return _build(cls, head, data, npz, js)

    def _check_description(self) -> None:
        if self.component_names is not None:
            names = list(self.component_names)
            if len(names) != len(self.components) or not all(isinstance(n, str) for n in names):
                raise ValueError(f"Branch.component_names must be {len(self.components)} strings (one per "
                                 f"recorded component), got {self.component_names!r}")
        if not isinstance(self.units, dict) or not all(isinstance(k, str) and isinstance(v, str)
                                                       for k, v in self.units.items()):
            raise ValueError(f"Branch.units must map array names to unit texts (str -> str), got {self.units!r}")
        if not isinstance(self.meta, dict):
            raise ValueError(f"Branch.meta must be a dict, got {type(self.meta).__name__}")

    # ------------------------------------------------------------------ xarray / netCDF
    def to_xarray(self) -> Any:
        """The branch as an ``xarray.Dataset`` (xarray is imported here, not with gfbjax).

        Dimensions: ``point`` (P; coordinate ``lam`` along it), ``component`` (k; coordinate ``component`` =
        the component names, or the state indices when unnamed, and ``state_index``), ``multiplier`` (n) and,
        when there are special points, ``special`` (S).  Data variables: every per-point array of the npz
        (``multipliers`` split into ``multipliers_real`` and ``multipliers_imag``, because netCDF has no
        complex type), each with ``attrs["units"]`` from :attr:`units`; the special points as ``special_type``,
        ``special_lam``, ``special_lam_error``, ``special_index``, ``special_located``, ``special_residual``,
        ``special_period``, ``special_angle``, ``special_omega`` (NaN where not defined), ``flagged`` (see
        :attr:`flagged`) and, when every spectrum has n values,
        ``special_spectrum_real``/``_imag`` (special, multiplier).  Attributes: ``format``, ``version``,
        ``kind``, ``outcome``, ``message``, ``m`` and ``accuracy_tol`` (when set), ``components``, ``units`` (JSON)
        and every key of
        :attr:`meta` as ``meta_<key>``: strings and numbers as they are, anything else (dicts, lists, booleans,
        None) as a JSON string.  The full states (``states``) are not included; they stay in the npz.
        """
        import xarray as xr

        self._check_description()
        P, k = len(self), len(self.components)
        n = self.multipliers.shape[1] if self.multipliers.ndim == 2 else 0
        names = list(self.component_names) if self.component_names is not None else [str(c) for c in self.components]

        def var(dims, values, key):
            return (dims, np.asarray(values), {"units": self.units[key]} if key in self.units else {})

        mu = np.asarray(self.multipliers, complex).reshape(P, n)
        data = {
            "period": var(("point",), self.period, "period"),
            "l2": var(("point",), self.l2, "l2"),
            "xmax": var(("point", "component"), np.reshape(self.xmax, (P, k)), "xmax"),
            "xmin": var(("point", "component"), np.reshape(self.xmin, (P, k)), "xmin"),
            "multipliers_real": var(("point", "multiplier"), mu.real, "multipliers"),
            "multipliers_imag": var(("point", "multiplier"), mu.imag, "multipliers"),
            "stable": var(("point",), np.asarray(self.stable, bool), "stable"),
            "trivial_error": var(("point",), self.trivial_error, "trivial_error"),
            "newton_iterations": var(("point",), np.asarray(self.newton_iterations, np.int32), "newton_iterations"),
            "ds": var(("point",), self.ds, "ds"),
            "tangent_lam": var(("point",), self.tangent_lam, "tangent_lam"),
            "flagged": (("point",), np.asarray(self.flagged, bool),
                        {"long_name": "not trusted (Branch.flagged): trivial multiplier farther than "
                                      "accuracy_tol from +1, monitor at or below its minimum, mesh error above "
                                      "mesh_tol, a spurious multiplier of unresolved fast modes above stiff_tol, or "
                                      "multipliers not resolved to multiplier_tol"}),
        }
        if self.mesh_error is not None:
            data["mesh_error"] = (("point",), np.asarray(self.mesh_error, float),
                                  {"long_name": "estimated collocation mesh error, relative to 1 + max|x|",
                                   "mesh_tol": float(self.mesh_tol)})
        if self.stiff_modulus is not None:
            data["stiff_modulus"] = (("point",), np.asarray(self.stiff_modulus, float),
                                     {"long_name": "largest modulus this mesh gives the fast modes' Floquet "
                                                   "multipliers (exactly about 0; 0: resolved)",
                                      "stiff_tol": float(self.stiff_tol)})
        if self.multiplier_error is not None:
            data["multiplier_error"] = (("point",), np.asarray(self.multiplier_error, float),
                                        {"long_name": "estimated error of the deciding Floquet multipliers on this "
                                                      "mesh (frozen model, mode defects, halved intervals)",
                                         "multiplier_tol": float(self.multiplier_tol)})
        if self.monitor is not None and self.monitor_info is not None:
            info = self.monitor_info
            data["monitor"] = (("point",), np.asarray(self.monitor, float),
                               {"long_name": f"{info['name']} (minimum {info['minimum']:g})",
                                **({"units": info["unit"]} if info.get("unit") else {})})
        lam_attrs = {"long_name": "continuation parameter"}
        if "lam" in self.units:
            lam_attrs["units"] = self.units["lam"]
        coords: dict[str, Any] = {
            "lam": (("point",), np.asarray(self.lam, float), lam_attrs),
            "component": (("component",), np.asarray(names, str)),
            "state_index": (("component",), np.asarray(self.components, np.int64).reshape(k)),
        }
        if self.special:
            sp = self.special
            nan = math.nan

            def num(v):
                return nan if v is None else float(v)

            data.update({
                "special_type": (("special",), np.asarray([s.type for s in sp], str)),
                "special_lam": (("special",), np.asarray([float(s.lam) for s in sp]), lam_attrs),
                "special_index": (("special",), np.asarray([int(s.index) for s in sp], np.int64)),
                "special_located": (("special",), np.asarray([bool(s.located) for s in sp], bool)),
                "special_residual": (("special",), np.asarray([num(s.residual) for s in sp])),
                "special_lam_error": (("special",), np.asarray([num(s.lam_error) for s in sp]),
                                      {**lam_attrs, "long_name": "estimated error of special_lam (SpecialPoint)"}),
                "special_period": (("special",), np.asarray([num(s.period) for s in sp])),
                "special_angle": (("special",), np.asarray([num(s.angle) for s in sp])),
                "special_omega": (("special",), np.asarray([num(s.omega) for s in sp])),
            })
            spectra = [np.asarray(s.spectrum, complex).ravel() for s in sp]
            if n and all(z.size == n for z in spectra):
                z = np.stack(spectra)
                data["special_spectrum_real"] = (("special", "multiplier"), z.real)
                data["special_spectrum_imag"] = (("special", "multiplier"), z.imag)
        attrs: dict[str, Any] = {"format": FORMAT, "version": FORMAT_VERSION, "kind": self.kind,
                                 "outcome": str(self.outcome), "message": self.message,
                                 "components": np.asarray(self.components, np.int64).reshape(k),
                                 "units": json.dumps(self.units)}
        if self.m is not None:
            attrs["m"] = int(self.m)
        if self.accuracy_tol is not None:
            attrs["accuracy_tol"] = float(self.accuracy_tol)
        if self.collocation is not None:
            attrs["collocation"] = self.collocation
        for key, v in self.meta.items():
            attrs[f"meta_{key}"] = _attr(v)
        return xr.Dataset(data, coords=coords, attrs=attrs)

    def to_netcdf(self, path: str | Path) -> Path:
        """Write :meth:`to_xarray` to a netCDF-3 file with the scipy engine (no netCDF library needed); read it
        back with ``xarray.open_dataset(path)``.  Returns the path.

        netCDF-3 takes a dimension of length 0 for its one unlimited dimension, so for an empty branch ``point``
        is written as that, and the variables on other empty dimensions (no multipliers, no components: they
        hold no values) are left out."""
        path = Path(path)
        ds = self.to_xarray()
        empty = [d for d, size in ds.sizes.items() if size == 0 and d != "point"]
        if empty:
            ds = ds.drop_dims(empty)
        ds.to_netcdf(path, engine="scipy", unlimited_dims=["point"] if len(self) == 0 else None)
        return path


# ---------------------------------------------------------------------------------------------------- helpers
def _paths(path: str | Path) -> tuple[Path, Path]:
    path = Path(path)
    base = path.with_suffix("") if path.suffix in (".npz", ".json") else path
    return base.with_name(base.name + ".npz"), base.with_name(base.name + ".json")


def _json_default(o: Any) -> Any:
    """NumPy scalars and real arrays as numbers and lists; anything else is an error naming its type."""
    if isinstance(o, np.generic) and not np.iscomplexobj(o):
        return o.item()
    if isinstance(o, np.ndarray) and not np.iscomplexobj(o) and o.dtype != object:
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"a {type(o).__name__} is not JSON-able")


def _attr(v: Any) -> Any:
    """A netCDF attribute value: str and real numbers as they are, the rest as a JSON string."""
    if isinstance(v, str):
        return v
    if isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_)):
        return v
    return json.dumps(v, default=_json_default)


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def _read_head(js: Path, npz: Path) -> dict[str, Any]:
    """The JSON sidecar as a dict, checked to be a branch sidecar of a version this module reads."""
    if not js.is_file():
        raise BranchFileError(f"{js}: no such file (a branch is saved as {npz.name} + {js.name})")
    try:
        head = json.loads(js.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise BranchFileError(f"{js}: not valid JSON ({exc.msg} at line {exc.lineno} column {exc.colno})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise BranchFileError(f"{js}: cannot be read ({_one_line(exc)})") from None
    if not isinstance(head, dict):
        raise BranchFileError(f"{js}: not a branch file (a JSON {type(head).__name__}, not an object)")
    fmt = head.get("format")
    if fmt is None:
        if "command" in head:  # the summary a CLI command writes next to the branch
            raise BranchFileError(f"{js}: not a branch file (the summary of 'gfbjax {head['command']}'; the branch "
                                  "is branch.npz + branch.json)")
        legacy = {"kind", "components", "special"} <= head.keys() and ("outcome" in head or "reason" in head)
        if not legacy:
            raise BranchFileError(f"{js}: not a branch file (no \"format\": \"{FORMAT}\" and none of the keys of "
                                  "an older branch file)")
        head["version"] = 1 if "outcome" in head else 0
    elif fmt != FORMAT:
        raise BranchFileError(f"{js}: not a branch file (format {fmt!r}, expected {FORMAT!r})")
    version = head.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 0:
        raise BranchFileError(f"{js}: 'version' must be a non-negative integer, got {version!r}")
    if version > FORMAT_VERSION:
        raise BranchFileError(f"{js}: written by a newer gfbjax (format version {version}; this one reads up to "
                              f"{FORMAT_VERSION})")
    return head


def _read_npz(npz: Path) -> dict[str, np.ndarray]:
    if not npz.is_file():
        raise BranchFileError(f"{npz}: no such file (a branch is saved as {npz.name} + "
                              f"{npz.with_suffix('.json').name})")
    # the ways a truncated or corrupt archive shows up: zipfile (BadZipFile), numpy's header parser (ValueError,
    # EOFError), a pickle that allow_pickle=False refuses (ValueError), the zip's deflate stream (zlib.error)
    broken = (zipfile.BadZipFile, EOFError, ValueError, OSError, zlib.error, NotImplementedError)
    try:
        z = np.load(npz, allow_pickle=False)
    except broken as exc:
        raise BranchFileError(f"{npz}: not a readable npz archive, truncated or corrupt ({_one_line(exc)})") from None
    if not isinstance(z, np.lib.npyio.NpzFile):
        raise BranchFileError(f"{npz}: not an npz archive (a single .npy array)")
    try:
        with z:
            return {k: z[k] for k in z.files}
    except broken as exc:
        raise BranchFileError(f"{npz}: truncated or corrupt npz archive ({_one_line(exc)})") from None


def _get(head: dict[str, Any], key: str, types: type | tuple[type, ...], js: Path, what: str,
         default: Any = ...) -> Any:
    if key not in head:
        if default is ...:
            raise BranchFileError(f"{js}: not a branch file (no {key!r} key)")
        return default
    v = head[key]
    allowed = types if isinstance(types, tuple) else (types,)
    if not isinstance(v, allowed) or (isinstance(v, bool) and bool not in allowed):  # JSON true is not an int
        raise BranchFileError(f"{js}: {key!r} must be {what}, got {v!r:.80}")
    return v


_LEGACY_REASONS = (("max_points", Outcome.MAX_POINTS), ("stopped by callback", Outcome.STOPPED),
                   ("interrupted", Outcome.INTERRUPTED), ("start point did not converge", Outcome.START_FAILED),
                   ("step size below", Outcome.STEP_TOO_SMALL), ("left [lam_min, lam_max]", Outcome.REACHED_END),
                   ("reached", Outcome.REACHED_END))


def _legacy_outcome(reason: str) -> Outcome:
    """The outcome of a version-0 file's free-text reason (the texts the engine wrote then)."""
    for text, outcome in _LEGACY_REASONS:
        if text in reason:
            return outcome
    return Outcome.STOPPED


def _legacy_special(d: dict[str, Any]) -> dict[str, Any]:
    """A version-0 special-point dict as a version-1 record: ``multipliers`` -> ``spectrum``; the HOPF
    frequency was stored in ``angle``."""
    d = dict(d)
    d["spectrum"] = d.pop("multipliers", None)
    d.setdefault("located", False)
    if d.get("type") == "HOPF":
        d["omega"], d["angle"] = d.get("angle"), None
    return d


def _accuracy_tol(head: dict[str, Any], js: Path) -> float | None:
    tol = head.get("accuracy_tol")
    if tol is not None and (isinstance(tol, bool) or not isinstance(tol, (int, float)) or not tol > 0):
        raise BranchFileError(f"{js}: 'accuracy_tol' must be a positive number or null, got {tol!r}")
    return None if tol is None else float(tol)


def _monitor(head: dict[str, Any], data: dict[str, np.ndarray], P: int, npz: Path, js: Path) -> dict[str, Any]:
    info = head.get("monitor")
    if info is None:
        return {}
    if not (isinstance(info, dict) and isinstance(info.get("name"), str)
            and isinstance(info.get("minimum"), (int, float)) and not isinstance(info.get("minimum"), bool)):
        raise BranchFileError(f"{js}: 'monitor' must be null or an object with 'name' and a numeric 'minimum', "
                              f"got {info!r:.80}")
    values = data.get("monitor")
    if values is None or values.shape != (P,):
        raise BranchFileError(f"{npz}: {js.name} names a monitor but the array 'monitor' is absent or not "
                              f"({P},)")
    return {"monitor": values.astype(float), "monitor_info": dict(info)}


def _tolerance_array(head: dict[str, Any], data: dict[str, np.ndarray], P: int, npz: Path, js: Path,
                     array: str, tol_key: str, upper: float = math.inf) -> dict[str, Any]:
    """An array checked against a tolerance in the JSON (``mesh_error``/``mesh_tol``,
    ``stiff_modulus``/``stiff_tol``): both present and of P points, or the tolerance null (older files)."""
    tol = head.get(tol_key)
    if tol is None:
        return {}
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 < tol <= upper:
        raise BranchFileError(f"{js}: {tol_key!r} must be a number in (0, {upper:g}] or null, got {tol!r}")
    values = data.get(array)
    if values is None or values.shape != (P,):
        raise BranchFileError(f"{npz}: {js.name} gives {tol_key} but the array {array!r} is absent or not ({P},)")
    return {array: values.astype(float), tol_key: float(tol)}


def _collocation(head: dict[str, Any], js: Path) -> str | None:
    kind = head.get("collocation")
    if kind is not None and kind not in ("gauss", "radau"):
        raise BranchFileError(f"{js}: 'collocation' must be \"gauss\", \"radau\" or null, got {kind!r:.40}")
    return kind


def _build(cls: type[Branch], head: dict[str, Any], data: dict[str, np.ndarray], npz: Path, js: Path) -> Branch:
    version = head["version"]
    kind = _get(head, "kind", str, js, f"one of {KINDS}")
    if kind not in KINDS:
        raise BranchFileError(f"{js}: 'kind' must be one of {KINDS}, got {kind!r}")
    components = _get(head, "components", list, js, "a list of state indices")
    if not all(isinstance(c, int) and not isinstance(c, bool) for c in components):
        raise BranchFileError(f"{js}: 'components' must be a list of integers, got {components!r:.80}")
    if version == 0:
        reason = _get(head, "reason", str, js, "a string")
        outcome, message = _legacy_outcome(reason), reason
    else:
        text = _get(head, "outcome", str, js, "an outcome string")
        try:
            outcome = Outcome(text)
        except ValueError:
            raise BranchFileError(f"{js}: 'outcome' {text!r} is not one of {[o.value for o in Outcome]}") from None
        message = _get(head, "message", str, js, "a string", "")
    m = _get(head, "m", (int, type(None)), js, "an integer or null", None)
    names = _get(head, "component_names", (list, type(None)), js, "a list of strings or null", None)
    if names is not None and (len(names) != len(components) or not all(isinstance(s, str) for s in names)):
        raise BranchFileError(f"{js}: 'component_names' must be {len(components)} strings (one per component), "
                              f"got {names!r:.80}")
    units = _get(head, "units", dict, js, "an object of strings", {})
    if not all(isinstance(v, str) for v in units.values()):
        raise BranchFileError(f"{js}: 'units' must map array names to strings, got {units!r:.80}")
    meta = _get(head, "meta", dict, js, "an object", {})
    raw_special = _get(head, "special", list, js, "a list of special-point records")
    special = []
    for i, d in enumerate(raw_special):
        if not isinstance(d, dict):
            raise BranchFileError(f"{js}: special[{i}] must be an object, got {d!r:.80}")
        try:
            special.append(SpecialPoint.from_json(_legacy_special(d) if version == 0 else d))
        except (TypeError, ValueError, KeyError) as exc:
            raise BranchFileError(f"{js}: special[{i}] is not a special-point record ({_one_line(exc)})") from None
    keys = _get(head, "keys", list, js, "a list of npz keys", [])

    # ---- the arrays: present, of one length, and of the JSON's shape
    absent = [k for k in ARRAY_KEYS if k not in data]
    if absent:
        raise BranchFileError(f"{npz}: not a branch archive (no arrays {', '.join(absent)})")
    unlisted = [k for k in keys if k not in data]
    if unlisted:
        raise BranchFileError(f"{npz} does not belong to {js.name}: arrays {', '.join(unlisted[:5])} listed there "
                              "are absent")
    arrays: dict[str, np.ndarray] = {}
    for key in ARRAY_KEYS:
        a = data[key]
        ndim = 2 if key in _MATRIX_KEYS else 1
        if a.ndim != ndim:
            raise BranchFileError(f"{npz}: array {key!r} must have {ndim} dimension(s), has shape {a.shape}")
        if not (np.issubdtype(a.dtype, np.number) or a.dtype == bool):
            raise BranchFileError(f"{npz}: array {key!r} must be numeric, has dtype {a.dtype}")
        if key != "multipliers" and np.iscomplexobj(a):
            raise BranchFileError(f"{npz}: array {key!r} must be real, has dtype {a.dtype}")
        arrays[key] = a
    P = arrays["lam"].shape[0]
    for key, a in arrays.items():
        if a.shape[0] != P:
            raise BranchFileError(f"{npz}: arrays of different lengths ('lam' has {P} points, {key!r} has "
                                  f"{a.shape[0]})")
    for key in ("xmax", "xmin"):
        if arrays[key].shape[1] != len(components):
            raise BranchFileError(f"{npz}: {key!r} has {arrays[key].shape[1]} columns, but {js.name} lists "
                                  f"{len(components)} components")
    points = head.get("points", P)
    if points != P:
        raise BranchFileError(f"{npz} has {P} points but {js.name} says {points!r}: the two files are from "
                              "different saves")
    arrays["multipliers"] = arrays["multipliers"].astype(complex, copy=False)
    arrays["stable"] = arrays["stable"].astype(bool, copy=False)

    states = {k[6:]: v for k, v in data.items() if k.startswith("state_")} or None
    sp_states: list[dict[str, np.ndarray]] = []
    i = 0
    while any(k.startswith(f"special{i}_") for k in data):
        pre = f"special{i}_"
        sp_states.append({k[len(pre):]: v for k, v in data.items() if k.startswith(pre)})
        i += 1
    for j, s in enumerate(special):
        if not (isinstance(s.index, int) and 0 <= s.index <= P):
            raise BranchFileError(f"{js}: special[{j}] has index {s.index!r}, outside the {P} points of {npz.name}")
        if s.state is not None and not (isinstance(s.state, int) and 0 <= s.state < len(sp_states)):
            raise BranchFileError(f"{js}: special[{j}] refers to state {s.state!r}, but {npz.name} holds "
                                  f"{len(sp_states)} special states")
    return cls(kind, list(components), *(arrays[k] for k in ARRAY_KEYS), special=special, outcome=outcome,
               message=message, states=states, special_states=sp_states, m=m,
               component_names=None if names is None else list(names), units=dict(units), meta=meta,
               accuracy_tol=_accuracy_tol(head, js), **_monitor(head, data, P, npz, js),
               collocation=_collocation(head, js), **_tolerance_array(head, data, P, npz, js, "mesh_error", "mesh_tol"),
               **_tolerance_array(head, data, P, npz, js, "stiff_modulus", "stiff_tol", 1.0),
               **_tolerance_array(head, data, P, npz, js, "multiplier_error", "multiplier_tol"))
