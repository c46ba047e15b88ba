r"""Energy flow of a limit cycle, paper Sect. 3.3, Eq. (23)-(24); units of ``p0 R L c``.

Over one period of a cycle of the autonomous system (Eq. 21), with the sign convention of docs/model.md
(positive = energy leaving the rotor into the films and foils):

* ``W_fu`` — work of the unbalance force on the disc (rigid rotor: on the rotor), Eq. (23c);
* ``W_B = -2 \oint F_B \cdot dx_j`` — work the two journals do on their gas films (bearing force ``F_B`` per
  bearing, Eq. 7), Eq. (23a) with ``W_kb = 0``;
* ``W_cf = 2 \sum_i \oint c_f \dot q_i \, dq_i \; \Delta\theta`` — dissipation in the bump-foil dampers of both
  bearings, Eq. (23b): each strip i spans ``\Delta\theta`` of the circumference over the whole length L, so its
  damper force is ``c_f \dot q_i`` (pressure units, ``c_f = eta / (alpha_f Omega_bar)``, or ``eta / alpha_f``
  with ``Params.structural_damping = 0``, the paper's convention) times the strip area
  ``R L \Delta\theta``; the spring part integrates to zero on a closed orbit;
* ``W_cb = W_B - W_cf`` — net dissipation in the gas films, Eq. (24) (``W_fu = W_cf + W_cb`` with ``T_1 = T_2``).

The rotor is conservative (spring, gravity, constant loads), so ``W_fu = W_B`` on every periodic solution.  Each
work is a period integral of a *power* of the state, evaluated with the collocation quadrature itself: the
m collocation points of every mesh interval, where the collocation equations make ``x' = T f(x)`` exact.  On a
collocation solution the identity then holds to rounding: the kinetic-energy and shaft-spring terms are polynomials
of degree 2m - 1 per interval, integrated exactly by m-point Gauss (and by m-point Radau, exact to degree 2m - 2,
to the solution's own accuracy).  The quadrature must use the points the orbit was computed on: Gauss quadrature
of a Radau orbit samples x' = T f(x) where it does not hold (W_fu - W_B up to 7e-5 relative on an adapted mesh).

Unit conversions (docs/model.md): the gas force is in ``p0 R L`` and displacements in ``c``; the unbalance term of the
equations is an acceleration, so the force on the disc is ``(m_d / m_j) F_U / zeta = 2 mass_ratio F_U / zeta``
(rigid rotor, mass ``2 m_j`` per two bearings: ``2 F_U / zeta``).
"""
from __future__ import annotations

from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from .. import cont
from ..model import foil_drive, layout
from ..model.foil import foil_damping_coefficient, foil_rates
from ..model.reynolds import bearing_force
from ..model.rotor import unbalance_force
from ..params import Params

__all__ = ["CycleEnergy", "power", "cycle_energy", "orbit_energy", "branch_energy", "sign_changes"]


class CycleEnergy(NamedTuple):
    """Works over one period of a cycle [p0 R L c] (see the module docstring for signs)."""

    W_fu: Any
    W_B: Any
    W_cf: Any
    W_cb: Any


def power(s: Array, omega: Array, params: Params) -> Array:
    """Powers ``(P_fu, P_B, P_cf)`` [p0 R L c / t*] at one state ``s`` of the autonomous system (Eq. 21)."""
    lay = layout(params, oscillator=True)
    grid = lay.grid
    P = lay.pressures(s)
    q = lay.foil_deflection(s)
    r = lay.rotor(s)
    u, v = lay.oscillator_state(s)[0], lay.oscillator_state(s)[1]
    theta = grid.theta(params.theta0)
    F_B = bearing_force(P, theta, grid, params.gumbel_width, gumbel=True)
    if params.rotor == "rigid":
        v_j, v_u, to_force = r[2:4], r[2:4], 2.0 / params.zeta
    else:
        v_j, v_u, to_force = r[4:6], r[6:8], 2.0 * params.mass_ratio / params.zeta
    F_U = unbalance_force(omega, params.eps, u, v)
    qdot = foil_rates(q, foil_drive(P, grid, params), omega, params.alpha_f, params.eta, params.structural_damping)
    c_f = foil_damping_coefficient(omega, params.alpha_f, params.eta, params.structural_damping)
    return jnp.stack([to_force * jnp.dot(F_U, v_u), -2.0 * jnp.dot(F_B, v_j),
                      2.0 * grid.dtheta * c_f * jnp.sum(qdot * qdot)])


def _period_integrals(xm: Array, xi: Array, mesh: Array, T: Array, omega: Array, params: Params,
                      collocation: str = "gauss") -> Array:
    m = xi.shape[1] + 1
    sch = cont.Scheme(m, collocation)
    U = jnp.concatenate([xm[:-1, None], xi, xm[1:, None]], axis=1)
    X = jnp.einsum("ki,jin->jkn", sch.l, U)  # states at the collocation points
    pw = jax.vmap(jax.vmap(lambda x: power(x, omega, params)))(X)  # (N, m, 3)
    return T * jnp.einsum("j,k,jka->a", jnp.diff(mesh), sch.weights, pw)


def orbit_energy(orbit: cont.Orbit, params: Params, collocation: str = "gauss") -> CycleEnergy:
    """Works of one collocation orbit (``orbit.lam`` = Omega_bar, ``orbit.T`` the period in t*), computed on
    ``collocation`` points ("gauss" or "radau": those the orbit was computed on, ``cont.Scheme.kind``); pure JAX:
    jit-, grad- and vmap-safe in ``orbit`` and ``params``."""
    W_fu, W_B, W_cf = _period_integrals(orbit.xm, orbit.xi, orbit.mesh, orbit.T, orbit.lam, params, collocation)
    return CycleEnergy(W_fu, W_B, W_cf, W_B - W_cf)


cycle_energy = jax.jit(orbit_energy, static_argnames="collocation")


@partial(jax.jit, static_argnames="collocation")
def _batch(xm, xi, mesh, T, lam, params, collocation):
    # mesh: (P, N+1), one per point (adapted meshes)
    return jax.vmap(lambda a, b, g, c, d: _period_integrals(a, b, g, c, d, params, collocation))(xm, xi, mesh, T,
                                                                                               lam)


def branch_energy(branch: Any, params: Params) -> CycleEnergy:
    """Works of every point of a branch computed with ``save_states=True`` (arrays over the points), on the
    branch's own collocation points (``branch.collocation``; Gauss for files that do not record it)."""
    s = branch.states
    if s is None:
        raise ValueError("branch has no stored states: continue it with CycleSettings(save_states=True)")
    mesh = np.asarray(s["mesh"], float)
    if mesh.ndim == 1:  # files of earlier versions: one mesh shared by every point
        mesh = np.broadcast_to(mesh, (len(s["T"]), mesh.size))
    W = np.asarray(_batch(jnp.asarray(s["xm"]), jnp.asarray(s["xi"]), jnp.asarray(mesh), jnp.asarray(s["T"]),
                          jnp.asarray(s["lam"]), params, getattr(branch, "collocation", None) or "gauss"))
    return CycleEnergy(W[:, 0], W[:, 1], W[:, 2], W[:, 1] - W[:, 2])


def sign_changes(lam: np.ndarray, W: np.ndarray) -> list[dict[str, float]]:
    """Speeds where ``W`` changes sign along a branch (linear interpolation between consecutive points), each with
    its direction: ``{"Omega_bar": ..., "from": "+" or "-"}``."""
    lam, W = np.asarray(lam, float), np.asarray(W, float)
    out = []
    for i in range(len(W) - 1):
        a, b = W[i], W[i + 1]
        if np.isfinite(a) and np.isfinite(b) and a * b < 0:
            out.append({"Omega_bar": float(lam[i] + (lam[i + 1] - lam[i]) * a / (a - b)), "from": "+" if a > 0 else "-"})
    return out
