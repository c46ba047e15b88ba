r"""Foil design at one speed: the limit cycle, its energy and stability as functions of the foil properties, with
exact gradients (paper Sect. 3.3; issue 5).

The design variables are the bump-foil compliance ``alpha_f`` (``k_f_bar = 1/alpha_f``) and the structural loss
factor ``eta`` (``c_f_bar = eta k_f_bar / Omega_bar``), both dimensionless, inside the paper's bounds
(Appendix A2): ``0.005 <= alpha_f <= 2``, ``0.0001 <= eta <= 10`` (:data:`gfbjax.limits.DESIGN_ALPHA_F`,
:data:`gfbjax.limits.DESIGN_ETA`).  The two objectives of the paper:

* OBJ1: maximise ``W_cb``, the energy the gas films dissipate per cycle [p0 R L c] (the paper minimises
  ``1/W_cb``);
* OBJ2: minimise ``max|mu|``, the largest non-trivial Floquet multiplier modulus (< 1: the cycle is stable).

:class:`FoilDesign` solves the cycle at fixed speed by collocation Newton, warm-started from the last cycle it
computed, and (on request) differentiates both objectives through the converged solution
(:mod:`gfbjax.cont`, implicit derivatives; both linear solvers).  It counts limit-cycle solves and gradient evaluations, the currency in which the
optimisers are compared.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import cont
from ..cont import Orbit
from ..cont._collocation import COLLOCATION_POINTS
from ..analyses.cycles import gfb_cycle_problem, unbalance_response_start
from ..limits import NoSolutionError
from ..analyses.energy import CycleEnergy, orbit_energy
from .. import limits
from ..params import ParameterError, Params, check_params

__all__ = ["FOIL_BOUNDS", "DESIGN_VARIABLES", "CycleEvaluation", "CycleNotConverged", "FoilDesign", "W_cb_of"]

DESIGN_VARIABLES = ("alpha_f", "eta")
#: The design variables' ranges, as ``{name: (lo, hi)}``: paper Appendix A2, defined in :mod:`gfbjax.limits`.
FOIL_RANGES = {"alpha_f": limits.DESIGN_ALPHA_F, "eta": limits.DESIGN_ETA}
FOIL_BOUNDS = {name: (rng.lo, rng.hi) for name, rng in FOIL_RANGES.items()}


class CycleNotConverged(NoSolutionError):
    """Newton found no cycle at these foil properties (counted as a solve)."""


def W_cb_of(orbit: Orbit, params: Params, collocation: str = "gauss") -> jax.Array:
    """W_cb of a collocation orbit [p0 R L c] (the OBJ1 functional, pure JAX), on the ``collocation`` points the
    orbit was computed on."""
    return orbit_energy(orbit, params, collocation).W_cb


# W_cb on each kind of points, one object each: the gradient kernels take the functional as a static argument and
# compile once per object, so every design shares them
_W_CB_ON = {kind: functools.partial(W_cb_of, collocation=kind) for kind in COLLOCATION_POINTS}


#: the multiplier error above which an evaluation's max_mu is not resolved (``cont.CycleSettings.multiplier_tol``)
MULTIPLIER_TOL = cont.CycleSettings().multiplier_tol


@dataclass
class CycleEvaluation:
    """One cycle at ``(alpha_f, eta)`` and speed ``omega`` (Omega_bar).

    energy: works per cycle [p0 R L c]; multipliers: Floquet multipliers (decreasing modulus; all of them with the
    dense solver, the leading ones (block Krylov) with the sparse one); max_mu: largest non-trivial modulus;
    grad_W_cb, grad_max_mu: derivatives with respect to (alpha_f, eta) when requested, else None.
    stiff_modulus, multiplier_error: whether the mesh resolves the multipliers (``cont.multiplier_estimates``:
    the frozen-coefficient model, the Floquet modes' defects and their change on halved intervals): with
    ``multiplier_error`` above 1e-3 max_mu and its gradient are not those of the cycle (at low speed on N = 16
    they are those of the film's fast modes, which collocation puts near the unit circle): raise N.  NaN: not
    estimated."""

    alpha_f: float
    eta: float
    omega: float
    orbit: Orbit
    energy: CycleEnergy
    multipliers: np.ndarray
    max_mu: float
    stable: bool
    newton_iterations: int
    grad_W_cb: np.ndarray | None = None
    grad_max_mu: np.ndarray | None = None
    stiff_modulus: float = math.nan
    multiplier_error: float = math.nan

    @property
    def resolved(self) -> bool:
        """max_mu is resolved by the mesh (multiplier_error at most 1e-3; True where not estimated)."""
        return not self.multiplier_error > MULTIPLIER_TOL

    @property
    def W_cb(self) -> float:
        return float(self.energy.W_cb)


#: Relative distance past a design bound that :func:`check_foil` treats as rounding and moves onto the bound
#: (an optimiser working in log variables lands on ``exp(log(10)) = 10.000000000000002``).
BOUND_ROUNDING = 1e-12


def _onto_bound(value: Any, rng: limits.Range) -> Any:
    if limits.is_traced(value):
        return value
    try:
        v = float(value)
    except (TypeError, ValueError):
        return value  # the range check names the field
    if math.isfinite(v):
        if rng.hi is not None and rng.hi < v <= rng.hi * (1.0 + BOUND_ROUNDING):
            return float(rng.hi)
        if rng.lo is not None and rng.lo * (1.0 - BOUND_ROUNDING) <= v < rng.lo:
            return float(rng.lo)
    return value


def check_foil(alpha_f: float, eta: float) -> tuple[float, float]:
    """ParameterError unless (alpha_f, eta) lie inside :data:`FOIL_BOUNDS` (NumPy and concrete JAX scalars are
    accepted); returns them as Python floats.  A value past a bound by rounding only (relative
    :data:`BOUND_ROUNDING`) is returned as the bound itself."""
    return (limits.DESIGN_ALPHA_F.check(_onto_bound(alpha_f, limits.DESIGN_ALPHA_F)),
            limits.DESIGN_ETA.check(_onto_bound(eta, limits.DESIGN_ETA)))


class FoilDesign:
    """Limit cycle of ``params`` at speed ``omega`` (Omega_bar) as a function of (alpha_f, eta).

    m, N: collocation points and mesh intervals; ``collocation``: "gauss" (default) or "radau"
    (``cont.CycleSettings``).  At low speed N = 16 resolves neither the film's fast modes (Gauss points give
    them spurious multipliers, which on the default grid exceed the physical ones below Omega_bar ~ 0.25 and so
    become ``max_mu``) nor the rotor's oscillation over the long period (Radau points damp it away): raise N
    there (README, "Fast and unresolved modes"); linear_solver: ``cont.DenseCondensation()``,
    ``cont.SparseSweep()`` or None (automatic: sparse on fine grids).  ``orbit``: a first guess (else
    :func:`gfbjax.analyses.cycles.unbalance_response_start`: the linear forced response at the given params, or a
    cycle reached by ramping the unbalance up when that response would close the film).  ``gradient_mode``: 'adjoint' (one transposed solve per objective, for
    every parameter at once) or 'tangent' (one solve per design variable); both work with either linear solver
    and agree to rounding ('auto' = 'adjoint').  Counters: ``n_solves`` (cycle solves, failed ones included),
    ``n_newton_steps`` (Newton steps of those solves, each converged solve's final residual check included) and
    ``n_gradients``.
    """

    def __init__(self, params: Params, omega: float, *, m: int = 4, N: int = 16, linear_solver: cont.LinearSolver | None = None,
                 orbit: Orbit | None = None, newton_tol: float = 1e-9, newton_max_iter: int = 10,
                 gradient_mode: str = "auto", collocation: str = "gauss"):
        check_params(params)
        omega = limits.SPEED.check(omega, "omega")
        if gradient_mode not in ("auto", "adjoint", "tangent"):
            raise ParameterError(f"gradient_mode = {gradient_mode!r} is not one of ('auto', 'adjoint', 'tangent')")
        try:
            self.settings = cont.CycleSettings(m=m, N=N, linear_solver=linear_solver, newton_tol=newton_tol,
                                               newton_step_tol=newton_tol, newton_max_iter=newton_max_iter,
                                               collocation=collocation)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self.params, self.omega = params, float(omega)
        self.scheme = cont.Scheme(m, collocation)
        self._W_cb = _W_CB_ON[self.scheme.kind]
        problem = gfb_cycle_problem(params)
        cont.bind_solver(problem, self.scheme, self.settings)  # a bad solver fails here
        try:
            cont.check_cycle_size(problem, N, m, self.settings)
        except ValueError as exc:
            raise ParameterError(str(exc)) from None
        self.gradient_mode = "adjoint" if gradient_mode == "auto" else gradient_mode
        if orbit is None:  # the linear response, or at a large unbalance a cycle reached by ramping the unbalance
            try:
                orbit, _ = unbalance_response_start(params, self.omega, self.settings)
            except NoSolutionError as exc:
                raise CycleNotConverged(str(exc)) from None
        self.orbit = self._at_speed(orbit)
        self.n_solves = 0
        self.n_newton_steps = 0
        self.n_gradients = 0
        self._memo: dict[str, Any] = {}  # Floquet warm starts from evaluation to evaluation

    def _at_speed(self, orbit: Orbit) -> Orbit:
        # Explicit dtype: a weakly typed T or lam would compile every kernel a second time for the Newton iterates.
        z = orbit.xm.dtype
        return Orbit(orbit.mesh, orbit.xm, orbit.xi, jnp.asarray(2 * np.pi / self.omega, dtype=z),
                     jnp.asarray(self.omega, dtype=z))

    def set_speed(self, omega: float, orbit: Orbit | None = None) -> None:
        """Move to another speed; the next solve starts from ``orbit`` (default: the last cycle, period
        rescaled to ``2 pi / omega``)."""
        self.omega = limits.SPEED.check(omega, "omega")
        self.orbit = self._at_speed(self.orbit if orbit is None else orbit)

    def params_at(self, alpha_f: float, eta: float) -> Params:
        return eqx.tree_at(lambda p: (p.alpha_f, p.eta), self.params,
                           (jnp.asarray(float(alpha_f)), jnp.asarray(float(eta))))

    def evaluate(self, alpha_f: float, eta: float, *, gradient: bool = False,
                 guess: Orbit | None = None, phase_reference: Orbit | None = None) -> CycleEvaluation:
        """Solve the cycle at (alpha_f, eta) from ``guess`` (default: the last cycle) and evaluate both
        objectives; ``gradient=True`` adds their derivatives.  ``phase_reference``: the orbit of the integral
        phase condition (default: the start).  The discrete cycles form a one-parameter family of phase shifts
        along which the works vary at the size of the discretisation error, so solves that must agree to rounding
        from different starts (maps reached along different paths) need one common reference.
        Raises :class:`CycleNotConverged`."""
        alpha_f, eta = check_foil(alpha_f, eta)
        p = self.params_at(alpha_f, eta)
        problem = gfb_cycle_problem(p)
        start = self.orbit if guess is None else self._at_speed(guess)
        con = None if phase_reference is None else cont.natural_constraint(self._at_speed(phase_reference),
                                                                           self.omega)
        self.n_solves += 1
        sol, lin = cont.correct_cycle(problem, start, con, settings=self.settings)
        self.n_newton_steps += int(sol.iterations) + int(sol.converged)
        if not sol.converged:
            raise CycleNotConverged(f"no cycle at alpha_f={alpha_f:.6g}, eta={eta:.6g}, Omega_bar={self.omega}: "
                                    f"Newton {sol.outcome} after {int(sol.iterations)} iterations")
        orbit = sol.x
        self.orbit = orbit
        an = cont.analyse(problem, lin, self.settings.floquet, self._memo)
        mu = an["spectrum"]
        nt = cont.nontrivial(mu, problem.n_trivial)
        stiff, mu_error = cont.multiplier_estimates(problem.f, problem.args, orbit, self.scheme, lin, mu, an["modes"],
                                                    problem.n_trivial,
                                                    cont.bind_solver(problem, self.scheme, self.settings).linearise)
        ev = CycleEvaluation(float(alpha_f), float(eta), self.omega, orbit,
                             CycleEnergy(*(float(w) for w in orbit_energy(orbit, p, self.scheme.kind))), mu,
                             float(np.max(np.abs(nt))), bool(np.all(np.abs(nt) < 1.0)), int(sol.iterations),
                             stiff_modulus=stiff, multiplier_error=mu_error)
        if gradient and self.gradient_mode == "adjoint":
            self.n_gradients += 1
            g = cont.adjoint_gradient(problem, lin, self.scheme, self._W_cb)
            _, gm = cont.multiplier_gradient(problem, lin, self.scheme)
            ev.grad_W_cb = np.array([float(getattr(g, k)) for k in DESIGN_VARIABLES])
            ev.grad_max_mu = np.array([float(getattr(gm, k)) for k in DESIGN_VARIABLES])
        elif gradient:
            self.n_gradients += 1
            dargs = self._directions(p)
            tangents = cont.orbit_sensitivities(problem, lin, dargs, self.scheme)
            ev.grad_W_cb = cont.functional_derivatives(self._W_cb, orbit, p, tangents, dargs)
            mu0, dmu = cont.multiplier_derivatives(problem, lin, self.scheme, tangents, dargs)
            ev.grad_max_mu = np.array([np.real(np.conj(mu0) * d) / abs(mu0) for d in dmu])
        return ev

    def _directions(self, p: Params) -> list[Params]:
        zero = jax.tree_util.tree_map(jnp.zeros_like, p)
        return [eqx.tree_at(lambda q: q.alpha_f, zero, jnp.asarray(1.0)),
                eqx.tree_at(lambda q: q.eta, zero, jnp.asarray(1.0))]
