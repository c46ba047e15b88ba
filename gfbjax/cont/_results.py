"""The result vocabulary of the engine: one enumeration of outcomes, and typed special-point records.

Every solver result (Newton corrections, static equilibria, transients) and every branch end carries an
:class:`Outcome`.  It is a ``str`` enumeration, so it compares equal to its value (``Outcome.CONVERGED ==
"converged"``) and is written to JSON as that string; inside compiled code it travels as the integer
:attr:`Outcome.code` and comes back with :meth:`Outcome.from_code`.  A human sentence with the details goes
alongside it (``message``), never instead of it.

Exceptions raised by user code (a bug in a vector field, a wrong shape) are *not* outcomes: they propagate.  Only
numerical failures of the solvers themselves (a singular or non-finite linear system, a Newton iteration that
diverges) are recorded as outcomes.
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

__all__ = ["Outcome", "SpecialPoint", "SPECIAL_TYPES"]


class Outcome(enum.StrEnum):
    """Why a solver or a branch stopped.

    Solvers: ``CONVERGED``; ``MAX_ITERATIONS`` (iteration budget spent); ``NONFINITE`` (a residual or step turned
    NaN/inf); ``DIVERGED`` (the Newton step grew by the divergence factor over its smallest value);
    ``LINEAR_SOLVE_FAILED`` (a singular block or a Krylov breakdown in the linear solver).
    Branches: ``REACHED_END`` (the parameter bound, reached exactly); ``MAX_POINTS``; ``STEP_TOO_SMALL`` (the
    corrector failed down to the smallest step; the message gives the corrector's own outcome);
    ``START_FAILED``; ``STOPPED`` (by the callback); ``INTERRUPTED`` (SIGINT/SIGTERM: the computed part is kept);
    ``ENDED_AT_HOPF`` (a family of cycles shrank to an equilibrium: it ends at that Hopf point, its last row);
    ``ENDED_AT_PD`` (a period-doubled family shrank onto the cycle of half its period: it ends at that period
    doubling, its last row).
    Physics: ``CONTACT`` (the film closed: no equilibrium or cycle with h_min > h_rub); ``RUB`` (a transient
    touched the foil); ``COMPLETED`` (a transient ran to its end); ``INTEGRATION_FAILED`` (the time integrator
    gave up); ``UNSTABLE`` (a design schedule stopped at an unstable optimum); ``NO_SOLUTION`` (no equilibrium or
    cycle was found).
    """

    CONVERGED = "converged"
    MAX_ITERATIONS = "max_iterations"
    NONFINITE = "nonfinite"
    DIVERGED = "diverged"
    LINEAR_SOLVE_FAILED = "linear_solve_failed"
    REACHED_END = "reached_end"
    MAX_POINTS = "max_points"
    STEP_TOO_SMALL = "step_too_small"
    START_FAILED = "start_failed"
    STOPPED = "stopped"
    INTERRUPTED = "interrupted"
    CONTACT = "contact"
    RUB = "rub"
    COMPLETED = "completed"
    UNSTABLE = "unstable"
    NO_SOLUTION = "no_solution"
    INTEGRATION_FAILED = "integration_failed"
    ENDED_AT_HOPF = "ended_at_hopf"
    ENDED_AT_PD = "ended_at_pd"
    RUNNING = "running"  # inside a compiled loop only: the iteration goes on

    @property
    def code(self) -> int:
        """Integer code of this outcome inside compiled code."""
        return _CODES[self]

    @classmethod
    def from_code(cls, code: Any) -> "Outcome":
        return _MEMBERS[int(code)]

    @property
    def ok(self) -> bool:
        """The computation did what was asked (a converged solve, a branch that reached its end or its point
        budget, a completed transient)."""
        return self in (Outcome.CONVERGED, Outcome.REACHED_END, Outcome.MAX_POINTS, Outcome.COMPLETED,
                        Outcome.ENDED_AT_HOPF, Outcome.ENDED_AT_PD)


_MEMBERS = list(Outcome)
_CODES = {o: i for i, o in enumerate(_MEMBERS)}

#: Special-point types: equilibria (FOLD, HOPF, BP), cycles (LPC fold of cycles, PD period doubling, NS
#: Neimark-Sacker / torus, BPC branch point of cycles).
SPECIAL_TYPES = ("FOLD", "HOPF", "BP", "LPC", "PD", "NS", "BPC")


@dataclass
class SpecialPoint:
    """A bifurcation found along a branch.

    type: one of :data:`SPECIAL_TYPES` (on a branch of cycles, a HOPF, or a PD as its last row, is where the
    family ended, shrunk onto what it was born from: ``Outcome.ENDED_AT_HOPF`` / ``ENDED_AT_PD``; that PD's
    period is the doubled cycles').  lam: the continuation parameter there.  index: row of the point in the
    branch arrays (a located point is inserted as a row; an unlocated one refers to the first point past the
    event).  period: cycle period (Hopf: 2 pi / omega; NaN for folds of equilibria).  spectrum: the Floquet
    multipliers (cycles) or eigenvalues of df/dx (equilibria) at the point, as in the branch arrays.
    located: the test function was driven to zero by the localisation solver; residual: its value at the returned
    point.  Not located with a finite residual: the sign change was bracketed to the step tolerance but the test
    function jumps there (its value is the residual): the location is good; omega (angle) is that of the pair that
    changed side across the bracket where the eigenvalues (multipliers) on its two sides match confidently, else
    that of the pair nearest the boundary at the point, and the other data are the point's.  That is the side
    the run reached second: a run in the other direction reports the other side's omega (angle), and the two
    differ by that value's change across the bracket (a new user saw a bracketed Hopf's frequency change with
    the run's direction; within the bracket neither value is more right).  Not
    located with a NaN residual: not localised at all; ``index`` then refers to the first point past the event.
    A bracketed BP deserves suspicion: the branch-point test also flips when the corrector jumps from one branch
    to a nearby one (an imperfect bifurcation with a large step), and then the points past it lie on the other
    branch; rerun with a smaller ``ds_max``.  (The driver itself halves a step whose localisation closes its
    bracket on two solutions that stay apart, and never reports such a point.)  Several bracketed points of one
    type within each other's error bars may be one crossing seen several times: a discrete branch that zig-zags
    within its own error (at a fold where mesh nodes cross a kink of f).  They are all reported, each with an error
    bar that covers the exact crossing; telling one event from several is left to a finer mesh.
    lam_error: an estimate of the error of ``lam``, in its units (NaN: none; also where the point was located or
    bracketed but every relocation on the other meshes failed, so that the discretisation's share is unknown).  The test function vanishes to
    ``locate_tol`` on *this* discretisation; the zero of the exact problem lies about ``lam_error`` away.  For a
    located cycle point: how far the zero moves when it is located again on the mesh with every interval halved
    or on the mesh staggered by half an interval (the larger move), plus the residual's share; for a located equilibrium only the residual's share (there is no discretisation).
    For a point bracketed but not located: the final bracket's width in the arclength (which bounds it in lam),
    plus the other meshes' share for cycles.  A branch point whose corrections failed next to it is placed where a
    regular bordered test function, interpolated across that gap, vanishes (where the curve's linear solver can
    do that: the dense one), and its error is that interpolation's; otherwise the bracket's width, widened to the
    noise of the multiplier test (|residual / slope|).  For those the discretisation's share is not estimated:
    a relocation next to a branch point would fail the same way.
    Not localised (``locate`` off, every correction failed, or two crossings no step could separate): the step's
    change in lam (a fold, where lam turns inside the step: the step's arclength, which bounds it).
    angle: NS, the argument of the critical multiplier in (0, pi) (rad); omega: HOPF, the imaginary part of the
    critical eigenvalue (per unit time of the problem).  state: index into ``Branch.special_states`` (the full
    state at the point).
    normal_form: normal-form data where computed (e.g. ``{"l1": first Lyapunov coefficient}``).
    """

    type: str
    lam: float
    index: int
    spectrum: np.ndarray
    located: bool
    residual: float = math.nan
    period: float = math.nan
    lam_error: float = math.nan
    angle: float | None = None
    omega: float | None = None
    state: int | None = None
    normal_form: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.type not in SPECIAL_TYPES:
            raise ValueError(f"special point type must be one of {SPECIAL_TYPES}, got {self.type!r}")

    @property
    def localisation(self) -> str:
        """How the point was placed, in one word for tables: ``"located"`` (its test function driven to zero),
        ``"bracketed"`` (a sign change pinned down to ``lam_error``, but the test function jumps there: no zero
        crossing, so the type-specific data come from one side, omega or angle from the pair that crossed where it
        can be matched), or ``"not localised"`` (reported at the
        first point past the event)."""
        if self.located:
            return "located"
        return "not localised" if math.isnan(self.residual) else "bracketed"

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict (complex spectrum as [re, im] pairs)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "spectrum":
                v = [[float(z.real), float(z.imag)] for z in np.asarray(v, complex)]
            elif isinstance(v, (np.floating, np.integer, np.bool_)):
                v = v.item()
            elif isinstance(v, float) and not math.isfinite(v):
                v = None if math.isnan(v) else v
            out[f.name] = v
        return out

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> "SpecialPoint":
        d = dict(d)
        d["spectrum"] = np.array([complex(a, b) for a, b in d.get("spectrum") or []], complex)
        for key in ("residual", "period", "lam_error"):
            if d.get(key) is None:
                d[key] = math.nan
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in known})
