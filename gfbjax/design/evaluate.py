r"""Foil design at one speed: the limit cycle, its energy and stability as functions of the foil properties, with
exact gradients (paper Sect. 3.3; issue 5).

The design variables are the bump-foil compliance ``alpha_f`` (``k_f_bar = 1/alpha_f``) and the structural loss
factor ``eta`` (``c_f_bar = eta k_f_bar / Omega_bar``), both dimensionless, inside the paper's bounds
(Appendix A2): ``0.005 < alpha_f < 2``, ``0.0001 < eta < 10``.  The two objectives of the paper:

* OBJ1: maximise ``W_cb``, the energy the gas films dissipate per cycle [p0 R L c] (the paper minimises
  ``1/W_cb``);
* OBJ2: minimise ``max|mu|``, the largest non-trivial Floquet multiplier modulus (< 1: the cycle is stable).

:class:`FoilDesign` solves the cycle at fixed speed by collocation Newton, warm-started from the last cycle it
computed, and (on request) differentiates both objectives through the converged solution
(:mod:`gfbjax.cont.implicit`).  It counts limit-cycle solves and gradient evaluations, the currency in which the
optimisers are compared.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import cont
from ..cont import collocation as col
from ..cont.floquet import nontrivial
from ..cont.implicit import (MultiplierModulus, adjoint_gradient, functional_derivatives,
                            multiplier_derivatives, orbit_sensitivities)
from ..analyses.cycles import gfb_cycle_problem, linear_response_start
from ..analyses.energy import CycleEnergy, orbit_energy
from ..params import ParameterError, Params

__all__ = ["FOIL_BOUNDS", "DESIGN_VARIABLES", "CycleEvaluation", "CycleNotConverged", "FoilDesign", "W_cb_of"]

DESIGN_VARIABLES = ("alpha_f", "eta")
FOIL_BOUNDS = {"alpha_f": (0.005, 2.0), "eta": (1e-4, 10.0)}  # paper Appendix A2


class CycleNotConverged(RuntimeError):
    """Newton found no cycle at these foil properties (counted as a solve)."""


def W_cb_of(orbit: col.Orbit, params: Params) -> jax.Array:
    """W_cb of a collocation orbit [p0 R L c] (the OBJ1 functional, pure JAX)."""
    return orbit_energy(orbit, params).W_cb


@dataclass
class CycleEvaluation:
    """One cycle at ``(alpha_f, eta)`` and speed ``omega`` (Omega_bar).

    energy: works per cycle [p0 R L c]; multipliers: Floquet multipliers (decreasing modulus; all of them on the
    dense backend, the leading ``n_multipliers`` on the sparse one); max_mu: largest non-trivial modulus;
    grad_W_cb, grad_max_mu: derivatives with respect to (alpha_f, eta) when requested, else None."""

    alpha_f: float
    eta: float
    omega: float
    orbit: col.Orbit
    energy: CycleEnergy
    multipliers: np.ndarray
    max_mu: float
    stable: bool
    newton_iterations: int
    grad_W_cb: np.ndarray | None = None
    grad_max_mu: np.ndarray | None = None

    @property
    def W_cb(self) -> float:
        return float(self.energy.W_cb)


def check_foil(alpha_f: float, eta: float) -> None:
    """ParameterError unless (alpha_f, eta) lie inside :data:`FOIL_BOUNDS`."""
    for name, v in (("alpha_f", alpha_f), ("eta", eta)):
        lo, hi = FOIL_BOUNDS[name]
        if not (np.isfinite(v) and lo <= v <= hi):
            raise ParameterError(f"{name} = {v!r} is outside the allowed range [{lo}, {hi}] (paper Appendix A2)")


class FoilDesign:
    """Limit cycle of ``params`` at speed ``omega`` (Omega_bar) as a function of (alpha_f, eta).

    m, N: collocation points and mesh intervals; linear_solver: as in :class:`gfbjax.cont.CycleSettings`
    ('auto': sparse on fine grids).  ``orbit``: a first guess (else the linear forced response at the given
    params).  ``gradient_mode``: 'adjoint' (one transposed solve per objective, dense backend only), 'tangent'
    (one solve per design variable, both backends) or 'auto' (adjoint where the backend is dense).  Counters:
    ``n_solves`` (cycle solves, failed ones included) and ``n_gradients``.
    """

    def __init__(self, params: Params, omega: float, *, m: int = 4, N: int = 16, linear_solver: str = "auto",
                 orbit: col.Orbit | None = None, newton_tol: float = 1e-9, newton_max_iter: int = 10,
                 gradient_mode: str = "auto"):
        if not (isinstance(omega, (int, float)) and 0.0 < omega <= 50.0):
            raise ParameterError(f"omega = {omega!r} is outside the allowed range (0, 50] (Omega_bar)")
        if gradient_mode not in ("auto", "adjoint", "tangent"):
            raise ParameterError(f"gradient_mode = {gradient_mode!r} is not one of ('auto', 'adjoint', 'tangent')")
        self.settings = cont.CycleSettings(m=m, N=N, linear_solver=linear_solver, newton_tol=newton_tol,
                                           newton_step_tol=newton_tol, newton_max_iter=newton_max_iter)
        self.params, self.omega = params, float(omega)
        self.scheme = col.Scheme(m)
        self._problem0 = gfb_cycle_problem(params)
        dense = not hasattr(cont.make_backend(self._problem0, self.scheme, self.settings),  # bad solver fails here
                            "linearise")
        if gradient_mode == "adjoint" and not dense:
            raise ParameterError("gradient_mode = 'adjoint' needs the dense backend (linear_solver='dense', or "
                                 "'auto' on a small grid); use 'tangent' with the sparse backend")
        self.gradient_mode = ("adjoint" if dense else "tangent") if gradient_mode == "auto" else gradient_mode
        if orbit is None:
            x_of_t, T, _ = linear_response_start(params, self.omega)
            orbit = col.orbit_from_function(x_of_t, T, self.omega, self.scheme, col.uniform_mesh(N))
        self.orbit = self._at_speed(orbit)
        self.n_solves = 0
        self.n_gradients = 0
        self._dargs = None

    def _at_speed(self, orbit: col.Orbit) -> col.Orbit:
        # Explicit dtype: a weakly typed T or lam would compile every kernel a second time for the Newton iterates.
        z = orbit.xm.dtype
        return col.Orbit(orbit.mesh, orbit.xm, orbit.xi, jnp.asarray(2 * np.pi / self.omega, dtype=z),
                         jnp.asarray(self.omega, dtype=z))

    def set_speed(self, omega: float, orbit: col.Orbit | None = None) -> None:
        """Move to another speed; the next solve starts from ``orbit`` (default: the last cycle, period
        rescaled to ``2 pi / omega``)."""
        self.omega = float(omega)
        self.orbit = self._at_speed(self.orbit if orbit is None else orbit)

    def params_at(self, alpha_f: float, eta: float) -> Params:
        return eqx.tree_at(lambda p: (p.alpha_f, p.eta), self.params,
                           (jnp.asarray(float(alpha_f)), jnp.asarray(float(eta))))

    def evaluate(self, alpha_f: float, eta: float, *, gradient: bool = False,
                 guess: col.Orbit | None = None) -> CycleEvaluation:
        """Solve the cycle at (alpha_f, eta) from ``guess`` (default: the last cycle) and evaluate both
        objectives; ``gradient=True`` adds their derivatives.  Raises :class:`CycleNotConverged`."""
        check_foil(alpha_f, eta)
        p = self.params_at(alpha_f, eta)
        problem = gfb_cycle_problem(p)
        backend = cont.make_backend(problem, self.scheme, self.settings)
        start = self.orbit if guess is None else self._at_speed(guess)
        self.n_solves += 1
        s = self.settings
        res = backend.newton(start, col.natural_constraint(start, self.omega), tol=s.newton_tol,
                             rtol_step=s.newton_step_tol, max_iter=s.newton_max_iter)
        if not res.converged:
            raise CycleNotConverged(f"no cycle at alpha_f={alpha_f:.6g}, eta={eta:.6g}, Omega_bar={self.omega}: "
                                    f"{res.reason}")
        orbit = res.orbit
        self.orbit = orbit
        mu = np.asarray(backend.multipliers(orbit))
        nt = nontrivial(mu, problem.n_trivial)
        ev = CycleEvaluation(float(alpha_f), float(eta), self.omega, orbit,
                             CycleEnergy(*(float(w) for w in orbit_energy(orbit, p))), mu,
                             float(np.max(np.abs(nt))), bool(np.all(np.abs(nt) < 1.0)), int(res.iterations))
        if gradient and self.gradient_mode == "adjoint":
            self.n_gradients += 1
            g = adjoint_gradient(problem, orbit, self.scheme, W_cb_of)
            mod = MultiplierModulus(problem.f, self.scheme)
            _, a = mod.weights(problem, orbit)
            gm = adjoint_gradient(problem, orbit, self.scheme, mod, a)
            ev.grad_W_cb = np.array([float(getattr(g, k)) for k in DESIGN_VARIABLES])
            ev.grad_max_mu = np.array([float(getattr(gm, k)) for k in DESIGN_VARIABLES])
        elif gradient:
            self.n_gradients += 1
            dargs = self._directions(p)
            tangents = orbit_sensitivities(problem, backend, orbit, dargs, self.scheme)
            ev.grad_W_cb = functional_derivatives(W_cb_of, orbit, p, tangents, dargs)
            mu0, dmu = multiplier_derivatives(problem, backend, orbit, self.scheme, tangents, dargs)
            ev.grad_max_mu = np.array([np.real(np.conj(mu0) * d) / abs(mu0) for d in dmu])
        return ev

    def _directions(self, p: Params) -> list[Params]:
        zero = jax.tree_util.tree_map(jnp.zeros_like, p)
        return [eqx.tree_at(lambda q: q.alpha_f, zero, jnp.asarray(1.0)),
                eqx.tree_at(lambda q: q.eta, zero, jnp.asarray(1.0))]
