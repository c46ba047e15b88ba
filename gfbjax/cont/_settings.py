"""Settings of a continuation run: step control and bounds (shared), the algorithm, and what is computed at each
point.  Every field is checked when the settings are built; a bad value raises ``ValueError`` naming the field and
its allowed range.

Algorithms are small objects, not strings: :class:`PseudoArclength` (the default; passes folds) and
:class:`Natural` (steps in the parameter itself; fails at folds).  The linear solver of cycles
(:class:`~._linear.DenseCondensation`, :class:`~._linear.SparseSweep`) and the Floquet method
(:class:`~._floquet.PeriodicQR`, :class:`~._floquet.TransferProduct`, :class:`~._floquet.Arnoldi`) are chosen the
same way; ``None`` means the automatic choice.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._checks import check_choices, check_flag, check_sign, store, store_range
from ._collocation import COLLOCATION_POINTS
from ._floquet import FloquetMethod
from ._linear import LinearSolver
from ._newton import NewtonSettings

__all__ = ["PseudoArclength", "Natural", "CycleSettings", "EquilibriumSettings"]


@dataclass(frozen=True)
class PseudoArclength:
    """Pseudo-arclength continuation (paper Eq. (30)): predictor along the unit tangent (or, with
    ``secant=True``, along the secant through the last two points), corrector on the hyperplane orthogonal to it
    at distance ds.  Passes folds.

    ``quadratic``: the prediction also follows the branch's curvature, estimated from the previous point and the
    tangent (the parabola through the previous point, tangent to the branch at the current one).  Only the
    starting guess moves: the hyperplane, and so the corrected point, are the same.  On the reference GFB branch
    it saves about one Newton iteration in four; it is dropped for a step where the curvature term would exceed a
    quarter of the step (a sharp turn, where the parabola is no guide)."""

    secant: bool = False
    quadratic: bool = True

    def __post_init__(self) -> None:
        for name in ("secant", "quadratic"):
            store(self, name, check_flag(f"PseudoArclength {name}", getattr(self, name)))

    def predict(self, space: Any, X: Any, X_prev: Any, tau: Any, ds: float, direction: int, dlam_max: float):
        """(prediction, constraint, ds) of the next step; ds is capped so that lam moves at most dlam_max."""
        d = tau
        if self.secant and X_prev is not None:
            sec = space.add(X, space.scale(X_prev, -1.0))
            d = space.scale(sec, 1.0 / float(np.sqrt(space.inner(sec, sec))))
        # cap the parameter change per step: the arclength metric can be dominated by T or by many states
        ds = min(ds, dlam_max / max(abs(float(space.lam(d))), 1e-300))
        pred = space.add(X, space.scale(d, ds))
        if self.quadratic and not self.secant and X_prev is not None:
            back = space.add(X_prev, space.scale(X, -1.0))
            h = float(np.sqrt(space.inner(back, back)))
            if h > 0.0:
                # X_prev = X - h d + h^2 k / 2 + O(h^3): the curvature term of the step is (ds/h)^2 (X_prev - X + h d)
                bend = space.scale(space.add(back, space.scale(d, h)), (ds / h) ** 2)
                if float(np.sqrt(space.inner(bend, bend))) <= 0.25 * ds:
                    pred = space.add(pred, bend)
        return pred, space.palc_constraint(X, d, ds, pred), ds, d


@dataclass(frozen=True)
class Natural:
    """Natural-parameter continuation: lam = lam_k + ds * direction, predictor by secant extrapolation of the last
    two points (the last point for the first step).  Fails at folds; the tangent is not used, so events are
    detected but not localised (they are reported at the first point past them, ``located=False``), and a branch
    cannot start from a bifurcation point (Hopf, PD) with it.  For checks and quick sweeps; use
    :class:`PseudoArclength` for results."""

    def predict(self, space: Any, X: Any, X_prev: Any, tau: Any, ds: float, direction: int, dlam_max: float):
        ds = min(ds, dlam_max)
        step = ds * float(direction)
        pred = X
        if X_prev is not None:
            sec = space.add(X, space.scale(X_prev, -1.0))
            pred = space.add(X, space.scale(sec, step / float(space.lam(X) - space.lam(X_prev))))
        return pred, space.natural_constraint(pred, float(space.lam(X)) + step), ds, None


ALGORITHMS = (PseudoArclength, Natural)


#: Smallest ``chord_tol``: below it the chord test would ask for more than the corrector's tolerances resolve.
CHORD_TOL_MIN = 1e-6


@dataclass(frozen=True)
class _StepSettings:
    """Fields shared by every continuation, with their common defaults (documented in the subclasses)."""

    ds: float = 0.05
    ds_max: float = 0.5
    direction: int = 1
    lam_min: float = -np.inf
    lam_max: float = np.inf
    dlam_max: float = np.inf
    fast_iter: int = 3
    grow: float = 1.5
    algorithm: Any = PseudoArclength()
    locate: bool = True
    max_angle: float = math.pi / 4
    event_refine: int = 6
    chord_tol: float = math.inf

    def _check_steps(self) -> None:
        put = functools.partial(store_range, self)
        inf = float("inf")
        put("ds", 0.0, inf, lo_open=True, hi_open=True)
        put("ds_min", 0.0, self.ds, lo_open=True)
        put("ds_max", self.ds, inf, hi_open=True)
        store(self, "direction", check_sign("direction", self.direction))
        put("max_points", 1, 10**7, integer=True)
        put("lam_min", -inf, inf, hi_open=True)
        put("lam_max", self.lam_min, inf, lo_open=True)
        put("dlam_max", 0.0, inf, lo_open=True)
        put("newton_tol", 0.0, 1.0, lo_open=True)
        put("newton_max_iter", 1, 1000, integer=True)
        put("fast_iter", 1, self.newton_max_iter, integer=True)
        put("grow", 1.0, 10.0)
        if not isinstance(self.algorithm, ALGORITHMS):
            raise ValueError(f"algorithm must be PseudoArclength(...) or Natural(), got {self.algorithm!r}")
        store(self, "locate", check_flag("locate", self.locate))
        put("locate_tol", 0.0, 1.0, lo_open=True)
        put("max_angle", 0.0, math.pi, lo_open=True)
        put("event_refine", 0, 60, integer=True)
        put("chord_tol", CHORD_TOL_MIN, inf)


@dataclass(frozen=True)
class CycleSettings(_StepSettings):
    """Settings of the continuation of periodic orbits.

    Discretisation (for starts built from samples, functions or Hopf points; a given start orbit keeps its own
    mesh): ``m`` collocation points per interval in [2, 7]; ``N`` mesh intervals >= 2.
    Steps: ``ds`` first arclength step (> 0), ``ds_min`` <= ds (the branch ends with ``STEP_TOO_SMALL`` when a
    failed correction halves the step below it), ``ds_max`` >= ds; after a correction in at most ``fast_iter``
    Newton iterations the step grows by ``grow`` in [1, 10]; ``dlam_max`` caps the predicted change of lam per
    step (the arclength metric can be dominated by T or by many states; inf = no cap).  ``chord_tol`` > 0 places
    the points where the branch bends: straight lines between recorded points (in the space of lam and each
    recorded component's max and min, each scaled by its range over the branch so far) stay within about
    ``chord_tol`` of the branch; the next step shrinks (at most by half) or may grow to that from the curvature of
    the last three points (never below ds_min), a step that misses by more than twice that is retried shorter, and
    with finite bounds the steps before three points exist (one after a recorded start) change lam by at most
    sqrt(chord_tol) (lam_max - lam_min); ``chord_tol`` in [1e-6, inf] (inf, the default: no such limit; below 1e-6
    it would ask for more than the corrector's tolerances resolve; ``_driver._chord_factor``, ``_chord_dlam``).
    Each quantity's scale is at least a tenth of its size (one that varies by less is not resolved) and a
    component's at least 1e-6 of the largest component (round-off next to zero is not a curve).  A lone component
    that starts to move after being exactly constant is given its first variations as its range, so that the test
    refines there, down to ds_min steps in the worst case (leave it out of the recorded ones, or chord_tol=inf).
    ``direction``: +1/-1, the initial orientation in lam.  Bounds: ``max_points`` recorded points; the branch ends
    (``REACHED_END``) when lam leaves [``lam_min``, ``lam_max``].
    Guarded steps: a step whose tangent turns by more than ``max_angle`` [rad] from the last one is rejected and
    retried with half the step (the corrector may have jumped to another branch, or the branch bends more sharply
    than the step resolves); a step with an event that cannot be located (its test function jumps: the signature
    of a jump between branches as much as of a coarse model) is retried with half the step up to
    ``event_refine`` times (counted until the event is passed) before the event is reported as not located; so
    is a step over which more multipliers (eigenvalues) cross the unit circle (imaginary axis) than the sign
    changes of the test functions account for (two events in one step cancel in a test function).  A branch
    point whose localisation fails only next to it (the corrections are singular there) is reported unlocated
    without refinement.  A step whose localisation closes its bracket on two solutions that stay apart (two
    branches: no event) is halved without that count, down to ``ds_min``, where the branch ends
    (``STEP_TOO_SMALL``, "jumps to another branch").  Neither check shrinks ds below ``ds_min``.
    Corrector: ``newton_tol`` (residual max-norm accepted after a small step), ``newton_step_tol`` (a step is small
    when |dx| <= tol (1 + max|x|)), ``newton_max_iter``.
    ``algorithm``: :class:`PseudoArclength` (default) or :class:`Natural`.
    Events: ``detect`` any of ("LPC", "PD", "NS", "BPC"); ``locate`` drives each test function to zero (tolerance
    ``locate_tol``, relative to the test values at the ends of the step when they are below 1) and inserts the
    located point in the branch.
    ``floquet``: a Floquet method (None: PeriodicQR with the dense solver, BlockKrylov(k=12) with the sparse one).
    ``linear_solver``: DenseCondensation(), SparseSweep(...) or None (sparse when the problem has a Jacobian
    pattern and n >= 80).  ``save_states``: keep every point's full orbit in the branch (restarts, energies).
    ``trivial_tol`` in (0, 1): a point whose trivial multiplier lies farther than this from +1 is flagged
    (``Branch.flagged``): its multipliers, so its stability label, are not accurate to that level.
    Mesh: every ``adapt`` points (0: never) the mesh is redistributed so that the estimated error of every
    interval is the same (:mod:`._mesh`, as AUTO does), and the orbit corrected on it; every point carries its
    estimated mesh error (``Branch.mesh_error``), and one above ``mesh_tol`` (relative to 1 + max|x|) is
    flagged: its orbit, period and multipliers are not resolved to that level (raise ``N``).
    ``collocation``: the collocation points, ``"gauss"`` (order 2m, as AUTO) or ``"radau"`` (order 2m - 1,
    L-stable: modes much faster than a mesh interval get multipliers near 0, as they should, where Gauss points
    put them near the unit circle, but modes oscillating within an interval are damped away; see
    :class:`~._collocation.Scheme`).  Every point carries the largest modulus the mesh gives its fast modes,
    whose exact multipliers are about 0 (``Branch.stiff_modulus``, :mod:`._resolution`), and one above
    ``stiff_tol`` in (0, 1] is flagged: a spurious multiplier lies in the band where stability, events and the
    trivial multiplier are decided (use ``collocation="radau"`` or more intervals).  It also carries the
    estimated error of the multipliers that decide stability, events and the leading modulus
    (``Branch.multiplier_error``), and one above ``multiplier_tol`` in (0, 1] is flagged: more intervals.
    """

    m: int = 4
    N: int = 20
    ds_min: float = 1e-6
    max_points: int = 100
    newton_tol: float = 1e-9
    newton_step_tol: float = 1e-9
    newton_max_iter: int = 8
    detect: tuple[str, ...] = ("LPC", "PD", "NS", "BPC")
    locate_tol: float = 1e-8
    floquet: FloquetMethod | None = None
    linear_solver: LinearSolver | None = None
    save_states: bool = False
    trivial_tol: float = 1e-5
    adapt: int = 3
    mesh_tol: float = 1e-4
    collocation: str = "gauss"
    stiff_tol: float = 0.9
    multiplier_tol: float = 1e-3

    def __post_init__(self) -> None:
        put = functools.partial(store_range, self)
        put("m", 2, 7, integer=True)
        put("N", 2, 10**6, integer=True)
        self._check_steps()
        put("newton_step_tol", 0.0, 1.0, lo_open=True)
        store(self, "detect", check_choices("detect", self.detect, ("LPC", "PD", "NS", "BPC")))
        if self.floquet is not None and not isinstance(self.floquet, FloquetMethod):
            raise ValueError(f"floquet must be PeriodicQR(), TransferProduct(), BlockKrylov(k), Arnoldi(k) or None, "
                             f"got {self.floquet!r}")
        put("trivial_tol", 0.0, 1.0, lo_open=True, hi_open=True)
        put("adapt", 0, 10**6, integer=True)
        put("mesh_tol", 0.0, 1.0, lo_open=True, hi_open=True)
        store(self, "save_states", check_flag("save_states", self.save_states))
        if not isinstance(self.collocation, str) or self.collocation not in COLLOCATION_POINTS:
            raise ValueError(f"collocation must be one of {COLLOCATION_POINTS}, got {self.collocation!r}")
        store(self, "collocation", str(self.collocation))
        put("stiff_tol", 0.0, 1.0, lo_open=True)
        put("multiplier_tol", 0.0, 1.0, lo_open=True)
        if self.linear_solver is not None and not isinstance(self.linear_solver, LinearSolver):
            raise ValueError(f"linear_solver must be DenseCondensation(), SparseSweep(...) or None (automatic), "
                             f"got {self.linear_solver!r}")

    @property
    def newton(self) -> NewtonSettings:
        return NewtonSettings(tol=self.newton_tol, atol_step=self.newton_step_tol, rtol_step=self.newton_step_tol,
                              max_iter=self.newton_max_iter)


@dataclass(frozen=True)
class EquilibriumSettings(_StepSettings):
    """Settings of the continuation of equilibria.

    Steps and bounds as in :class:`CycleSettings` (``ds``, ``ds_min``, ``ds_max``, ``direction``, ``max_points``,
    ``lam_min``, ``lam_max``, ``dlam_max``, ``chord_tol``, ``fast_iter``, ``grow``, ``algorithm``, ``max_angle``,
    ``event_refine``).
    Corrector: ``newton_tol`` (a step is small when |dy| <= tol (1 + max|y|); the residual is then accepted below
    max(1e3 tol, 1e-9)), ``newton_max_iter``.
    Events: ``detect`` any of ("FOLD", "HOPF", "BP"); ``locate``, ``locate_tol`` as for cycles.
    """

    ds_min: float = 1e-8
    max_points: int = 200
    newton_tol: float = 1e-11
    newton_max_iter: int = 10
    detect: tuple[str, ...] = ("FOLD", "HOPF", "BP")
    locate_tol: float = 1e-10

    def __post_init__(self) -> None:
        self._check_steps()
        store(self, "detect", check_choices("detect", self.detect, ("FOLD", "HOPF", "BP")))

    @property
    def newton(self) -> NewtonSettings:
        return NewtonSettings(tol=max(1e3 * self.newton_tol, 1e-9), atol_step=self.newton_tol,
                              rtol_step=self.newton_tol, max_iter=self.newton_max_iter)
