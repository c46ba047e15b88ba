"""Allowed ranges of the inputs, each defined once: the command line, the Python API and the design code all check
against the :class:`Range` objects of this module, so that a bound changed here changes everywhere.

A :class:`Range` knows its field name, its bounds (open or closed), its unit and whether it holds integers;
:meth:`Range.check` raises :class:`ParameterError` with a one-line message naming the field, the value and the range,
e.g. ``omega_bar = 60 is outside the allowed range (0, 50] (dimensionless speed Omega_bar = Omega t*)``.  Checks
accept Python numbers, NumPy scalars and concrete 0-d JAX arrays, and are skipped for JAX tracers (inside
``jit``/``vmap``/``grad`` a value is not known; the entry points check before tracing).  Callers may pass their own
label (an argument name such as ``omega_start`` or a command-line option such as ``--speed``).

Ranges of one solver's tolerances (``TransientSettings.rtol`` ...) stay next to their settings class; every range
that is a physical input, a speed, a grid, a foil bound or the size of a run lives here.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "NoSolutionError",
    "ParameterError",
    "Range",
    "is_traced",
    "check_real",
    # speeds and runs
    "SPEED", "SPEED_STEP", "LOAD_W", "REVOLUTIONS", "SETTLE_REVOLUTIONS", "ACCEL", "MAX_HISTORY_BYTES",
    "check_history",
    # grids
    "NX", "NZ", "MAX_DENSE_UNKNOWNS", "STATES", "n_states", "check_grid", "PLAIN_NX", "PLAIN_UNKNOWNS",
    # collocation
    "COLLOCATION_M", "MESH_N",
    # the system, SI
    "R", "L", "CLEARANCE", "MAX_CLEARANCE_OVER_R", "MU", "P0", "GRAVITY", "M_J", "M_D", "K_S_BAR", "ALPHA_F",
    "ETA", "BALANCE_GRADE", "OMEGA_R", "E_U", "THETA0", "LOAD", "GUMBEL_WIDTH", "LOAD_PER_BEARING", "POSITIVE",
    "POISSON",
    # dimensionless groups of Params
    "KAPPA", "ZETA", "SIGMA", "EPS", "W_EXT", "MASS_RATIO", "STRUCTURAL_DAMPING",
    # foil design
    "DESIGN_ALPHA_F", "DESIGN_ETA",
]


class ParameterError(ValueError):
    """Raised for an input outside its allowed range; the message names the field, its value and the range."""


class NoSolutionError(RuntimeError):
    """A solve that the user asked for found no solution (no static equilibrium at a start speed, no cycle at a
    design); the message says where and why.  Raised instead of returning garbage; the command line reports it in
    one line with exit status 1."""


def is_traced(value: Any) -> bool:
    """True for a JAX tracer (a value inside ``jit``/``vmap``/``grad``, unknown until run time)."""
    import jax

    return isinstance(value, jax.core.Tracer)


def _fmt(v: float | int) -> str:
    """Short text of a number that still reads back as the same value (``60``, ``0.3``, ``1e-12``)."""
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    s = f"{v:g}"
    return s if float(s) == v else f"{v:.10g}"  # 50.0000001 is not shown as 50; 0.0019050000000000002 as 0.001905


def _real(label: str, value: Any, integer: bool) -> float | int:
    """``value`` as a Python int or float: Python, NumPy and concrete 0-d JAX numbers; booleans, strings, arrays
    of more than one element and complex numbers are refused."""
    kind = "an integer" if integer else "a real number"
    if isinstance(value, (bool, np.bool_)):
        raise ParameterError(f"{label} must be {kind}, got {value!r}")
    if isinstance(value, (int, np.integer)):
        return int(value) if integer else float(value)
    if isinstance(value, float) and not integer:
        v = value
    else:
        try:
            arr = np.asarray(value)
        except Exception:  # noqa: BLE001 - any object numpy cannot read is not a number
            raise ParameterError(f"{label} must be {kind}, got {value!r}") from None
        if arr.ndim != 0:
            raise ParameterError(f"{label} must be a scalar, got shape {arr.shape} (use jax.vmap to batch)")
        if arr.dtype.kind in "iu":
            return int(arr) if integer else float(arr)
        if integer or arr.dtype.kind != "f":
            raise ParameterError(f"{label} must be {kind}, got {value!r}")
        v = float(arr)
    if not math.isfinite(v):
        raise ParameterError(f"{label} must be finite, got {_fmt(v)}")
    return v


def check_real(label: str, value: Any, *, integer: bool = False) -> Any:
    """``value`` as a finite Python float (int with ``integer``), any size; tracers are returned unchanged."""
    if is_traced(value):
        return value
    return _real(label, value, integer)


@dataclass(frozen=True)
class Range:
    """An allowed interval of one input.

    Attributes:
        name: field name used in messages (callers may pass another label, e.g. a command-line option).
        lo, hi: bounds; None for none (-inf, inf).
        lo_open, hi_open: the bound itself is excluded.
        unit: unit of the value, printed after it (``"m"``, ``"kg"``; empty for dimensionless values).
        integer: the value must be an integer (Python or NumPy; ``40.0`` is refused).
        what: what the value is, or why the range is what it is; printed in parentheses after the range.
    """

    name: str
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    integer: bool = False
    what: str = ""

    def interval(self) -> str:
        """The range as text, e.g. ``(0, 50]``; an unbounded end is open (``(0, inf)``): values must be finite."""
        left = "(" if self.lo_open or self.lo is None else "["
        right = ")" if self.hi_open or self.hi is None else "]"
        lo = "-inf" if self.lo is None else _fmt(self.lo)
        hi = "inf" if self.hi is None else _fmt(self.hi)
        return f"{left}{lo}, {hi}{right}"

    def __str__(self) -> str:
        u = f" {self.unit}" if self.unit else ""
        return f"{self.name} in {self.interval()}{u}"

    def contains(self, v: float) -> bool:
        """Whether the (finite, real) number ``v`` lies inside."""
        if self.lo is not None and (v <= self.lo if self.lo_open else v < self.lo):
            return False
        return not (self.hi is not None and (v >= self.hi if self.hi_open else v > self.hi))

    def message(self, value: float | int, label: str | None = None) -> str:
        """``'label = value unit is outside the allowed range (lo, hi] unit (what)'``."""
        u = f" {self.unit}" if self.unit else ""
        extra = f" ({self.what})" if self.what else ""
        return (f"{label or self.name} = {_fmt(value)}{u} is outside the allowed range {self.interval()}{u}"
                f"{extra}")

    def check(self, value: Any, label: str | None = None) -> Any:
        """Return ``value`` as a Python float (int for an integer range) if it is a finite number inside the range;
        raise :class:`ParameterError` otherwise.  A JAX tracer is returned unchanged (not checked)."""
        if is_traced(value):
            return value
        name = label or self.name
        v = _real(name, value, self.integer)
        if not self.contains(v):
            raise ParameterError(self.message(v, name))
        return v

    def check_all(self, values: Any, label: str | None = None) -> None:
        """Check every element of an array (or a scalar); the message names the first one outside.  Tracers are
        skipped."""
        if is_traced(values):
            return
        arr = np.asarray(values)
        if arr.ndim == 0:
            self.check(values, label)
            return
        for v in arr.ravel():
            self.check(v.item(), label)

    def with_bounds(self, **bounds: Any) -> "Range":
        """A copy with some fields changed, e.g. a bound that depends on another field (``c <= 0.05 R``)."""
        return dataclasses.replace(self, **bounds)


# -- speeds, loads and the length of a run ----------------------------------------------------------------------

#: Dimensionless speed ``Omega_bar = Omega t* = 6 mu Omega R^2 / (p0 c^2)`` (the bearing number).  The paper's
#: analyses stay below 1; 50 is a sanity bound (at the reference system, t* = 0.27 ms, it is 1.8 million rpm).
SPEED = Range("omega_bar", 0.0, 50.0, lo_open=True, what="dimensionless speed Omega_bar = Omega t*")
#: Speed step of a march in speed (optimised continuation).
SPEED_STEP = Range("d_omega", 0.0, 1.0, lo_open=True, what="speed step in Omega_bar")
#: Extra static specific load per bearing beyond gravity, ``W / (p0 L D)``.  20 is far beyond what a film of
#: ``h > 0`` carries at the speeds above (the static solver reports "contact" well before).
LOAD_W = Range("w", 0.0, 20.0, what="extra specific load W/(p0 L D) per bearing")
#: Length of a transient run in revolutions (simulate, run-up, and the revolutions a run-up acceleration implies).
REVOLUTIONS = Range("revolutions", 0.0, 1e6, lo_open=True)
#: Revolutions at the start speed before a run-up (``gfbjax runup --settle-revs``).
SETTLE_REVOLUTIONS = Range("settle revolutions", 0.0, 1e5)
#: Magnitude of the run-up angular acceleration ``a_bar = a t*^2``.  Above 100 a run from rest to the top speed
#: takes fewer than two revolutions (no transient to resolve); the smallest value follows from REVOLUTIONS.
ACCEL = Range("|accel|", 0.0, 100.0, lo_open=True, unit="per tau^2", what="angular acceleration a_bar = a t*^2")
#: Memory of the samples a transient run keeps (time, speed, h_min and rotor states per sample, plus the full
#: state with ``save_states``); runs that would need more are refused before they start.
MAX_HISTORY_BYTES = 4 * 2**30


def check_history(n_samples: float, bytes_per_sample: int, what: str = "the run") -> None:
    """ParameterError when ``n_samples`` samples of ``bytes_per_sample`` bytes exceed :data:`MAX_HISTORY_BYTES`."""
    need = n_samples * bytes_per_sample
    if not need <= MAX_HISTORY_BYTES:
        raise ParameterError(
            f"saved samples = {n_samples:.4g} of {what} ({need / 2**30:.3g} GiB) is outside the allowed range "
            f"[1, {MAX_HISTORY_BYTES // bytes_per_sample:.4g}] (at most {MAX_HISTORY_BYTES / 2**30:g} GiB of "
            "history: fewer revolutions, a larger acceleration or fewer samples per revolution)")


# -- grids ------------------------------------------------------------------------------------------------------

NX = Range("Nx", 16, 1024, integer=True,
           what="circumferential intervals over 2 pi; fewer than 16 cannot resolve the film's converging wedge")
NZ = Range("Nz", 2, 256, integer=True, what="axial intervals over the half length, at least 2")
#: Largest number of unknowns of a dense Newton Jacobian.  Every analysis of the foil-bearing system builds dense
#: n x n matrices (static and equilibrium Jacobians and their eigenvalues, the LU of the transient's implicit stages,
#: monodromy matrices): 8 n^2 bytes each (0.3 GB at this bound), several at once during ``jax.jacfwd`` (1.3 GB peak
#: measured at n = 4187, grid 200 x 20), and O(n^3) work per factorisation.  Beyond it the grid does not fit.
MAX_DENSE_UNKNOWNS = 6144
STATES = Range("states", 1, MAX_DENSE_UNKNOWNS, integer=True,
               what="dense n x n Jacobians; n = (Nx - 1)(Nz + 1) + rotor states")


def n_states(Nx: int, Nz: int, n_rotor: int, full_length: bool = False) -> int:
    """States of the foil-bearing system: (Nx - 1) Nz pressures (``full_length``: (Nx - 1)(2 Nz - 1), the whole
    bearing length at the same spacing), Nx - 1 foil strips and the rotor."""
    nz = 2 * Nz - 1 if full_length else Nz
    return (Nx - 1) * (nz + 1) + n_rotor


def check_grid(Nx: Any, Nz: Any, n_rotor: int, full_length: bool = False) -> tuple[int, int]:
    """Check the foil-bearing grid (each axis and the number of states, :func:`n_states`); returns ``(Nx, Nz)`` as
    ints."""
    nx, nz = NX.check(Nx), NZ.check(Nz)
    n = n_states(nx, nz, n_rotor, full_length)
    if not STATES.contains(n):
        raise ParameterError(f"grid Nx x Nz = {nx} x {nz} has {n} states, outside the allowed range "
                             f"[1, {MAX_DENSE_UNKNOWNS}] (dense n x n Jacobians: {8 * n * n / 2**30:.3g} GiB each at "
                             "this size; use a coarser grid)")
    return nx, nz


#: The plain 360-degree bearing's grid is periodic (no fixed foil end), so it needs fewer intervals.
PLAIN_NX = Range("Nx", 8, 1024, integer=True, what="circumferential intervals over 2 pi")
#: Its steady Newton solve has Nx Nz unknowns with a dense Jacobian: the same bound.
PLAIN_UNKNOWNS = Range("Nx * Nz", 16, MAX_DENSE_UNKNOWNS, integer=True,
                       what="the dense Newton Jacobian would not fit")

# -- collocation of periodic orbits -----------------------------------------------------------------------------

COLLOCATION_M = Range("m", 2, 7, integer=True, what="collocation points per mesh interval")
MESH_N = Range("N", 2, 10**5, integer=True, what="collocation mesh intervals")

# -- the system in SI units (gfbjax.SystemSpec) -----------------------------------------------------------------

R = Range("R", 0.0, 10.0, lo_open=True, unit="m")
L = Range("L", 0.0, 10.0, lo_open=True, unit="m")
#: Radial clearance; its upper bound is ``MAX_CLEARANCE_OVER_R * R`` (a clearance of 10% of R is no foil bearing).
MAX_CLEARANCE_OVER_R = 0.05
CLEARANCE = Range("c", 0.0, None, lo_open=True, unit="m", what="at most 5% of the radius R")
MU = Range("mu", 0.0, 1.0, lo_open=True, unit="Pa s")
P0 = Range("p0", 0.0, 1e8, lo_open=True, unit="Pa")
GRAVITY = Range("g", 0.0, 1e3, unit="m/s^2")
M_J = Range("m_j", 0.0, 1e5, lo_open=True, unit="kg")
M_D = Range("m_d", 0.0, 1e5, lo_open=True, unit="kg")
K_S_BAR = Range("k_s_bar", 0.0, 1e4, lo_open=True, what="shaft stiffness k_s t*^2 / m_d")
#: Bump-foil compliance; alpha_f = 0 would be a rigid foil with an infinite strip stiffness k_f = 1/alpha_f.
ALPHA_F = Range("alpha_f", 0.0, 100.0, lo_open=True, what="bump-foil compliance")
#: Foil loss factor; eta = 0 would make the foil equation (Eq. 10) algebraic (q' divides by eta): not an ODE.
ETA = Range("eta", 0.0, 100.0, lo_open=True, what="foil loss factor")
BALANCE_GRADE = Range("G", 0.0, 100.0, unit="mm/s", what="ISO 1940 balance grade")
OMEGA_R = Range("omega_r", 0.0, None, lo_open=True, unit="rad/s")
#: Unbalance eccentricity (the disc's mass eccentricity: not bounded by the clearance; SystemSpec warns above c).
E_U = Range("e_u", 0.0, None, unit="m")
THETA0 = Range("theta0", -2 * math.pi, 2 * math.pi, unit="rad")
LOAD = Range("load", 0.0, None, unit="N")
GUMBEL_WIDTH = Range("gumbel_width", 0.0, 0.1)
LOAD_PER_BEARING = Range("load_per_bearing", 0.0, None, lo_open=True, unit="N")
#: A positive length, modulus or pressure (bump-foil geometry); pass the field name as the label.
POSITIVE = Range("value", 0.0, None, lo_open=True)
POISSON = Range("nu", 0.0, 0.5, hi_open=True, what="Poisson's ratio")

# -- dimensionless groups (gfbjax.Params; see gfbjax.params for their definitions) ------------------------------

KAPPA = Range("kappa", 0.0, None, lo_open=True, what="R/L")
ZETA = Range("zeta", 0.0, None, lo_open=True, what="p0 R L t*^2 / (m_j c)")
SIGMA = Range("sigma", 0.0, None, what="g t*^2 / c")
EPS = Range("eps", 0.0, None, what="disc unbalance acceleration over c Omega^2")
W_EXT = Range("w_ext", 0.0, None, what="extra load over p0 R L")
STRUCTURAL_DAMPING = Range("structural_damping", 0.0, 1.0,
                           what="1: c_f = eta k_f / Omega_bar, 0: c_f = eta k_f (SystemSpec.foil_damping)")
MASS_RATIO = Range("mass_ratio", 0.0, None, lo_open=True, what="m_d / (2 m_j), Jeffcott rotor")

# -- foil design (gfbjax.design) --------------------------------------------------------------------------------

#: The paper's design bounds (Appendix A2), inside ALPHA_F and ETA.
DESIGN_ALPHA_F = Range("alpha_f", 0.005, 2.0, what="paper Appendix A2 design bounds")
DESIGN_ETA = Range("eta", 1e-4, 10.0, what="paper Appendix A2 design bounds")
