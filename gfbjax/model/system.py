"""The assembled GFB-rotor system: one pure vector field shared by equilibria, collocation, diffrax and design.

Forms (all jit-, vmap- and grad-safe; ``params`` is a :class:`gfbjax.params.Params` PyTree):

* :func:`vector_field` ``f(s, omega, params)`` — the autonomous system of Eq. (21)-(22): the core states plus the
  phase oscillator of Eq. (19); used for limit cycles of the unbalanced rotor at constant speed.
* :func:`balanced_vector_field` ``f(s, omega, params)`` — the core states with no unbalance (G0): equilibria,
  static analysis, Hopf points.
* :func:`forced_vector_field` ``f(tau, s, omega, params)`` — Eq. (17) with Eq. (15a), for time integration.
* :func:`runup_vector_field` ``f(tau, s, params, omega0, accel)`` — run-up at constant acceleration, Eq. (15b).

States and their order are documented in :mod:`gfbjax.model.grid`; :func:`layout` gives named views.  The model
options of :class:`gfbjax.SystemSpec` (``gumbel``, ``foil_springs``, ``axial_domain``) reach it as static fields of
``params`` and are applied by the module that owns each concept (:mod:`.reynolds`, :mod:`.foil`, :mod:`.grid`).
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array

from ..params import Params
from .foil import foil_rates, supported_drive
from .grid import Grid, StateLayout
from .reynolds import (ambient_clipped_rates, bearing_force, film_thickness, gauge, mean_gauge_pressure,
                       pressure_rates)
from .rotor import N_ROTOR, oscillator_rates, rotor_rates, unbalance_force, unbalance_force_runup

__all__ = [
    "grid_of",
    "layout",
    "film",
    "core_rates",
    "foil_drive",
    "vector_field",
    "balanced_vector_field",
    "forced_vector_field",
    "runup_vector_field",
    "initial_state",
    "plain_bearing_rates",
]


def grid_of(params: Params) -> Grid:
    """The foil bearing's grid for these parameters (``params.axial_domain``: half or full length)."""
    return Grid(params.Nx, params.Nz, periodic=False, full_length=params.axial_domain == "full")


def layout(params: Params, oscillator: bool = False) -> StateLayout:
    """State layout of the system; ``oscillator=True`` for the autonomous form of Eq. (21)."""
    return StateLayout(grid_of(params), N_ROTOR[params.rotor], oscillator)


def film(s: Array, params: Params) -> Array:
    """Film thickness h/c at all circumferential nodes, foil ends included (shape (Nx+1,))."""
    lay = layout(params)
    grid = lay.grid
    q = jnp.pad(lay.foil_deflection(s), 1)  # the foil is clamped at its fixed end: q = 0 there
    xj, yj = lay.journal(s)[0], lay.journal(s)[1]
    return film_thickness(grid.theta_nodes(params.theta0), xj, yj, q)


def foil_drive(P: Array, grid: Grid, params: Params) -> Array:
    """Load on each foil strip, ``max(p_m - 1, 0)`` [p0] (Eq. 9-10 with the Gumbel condition), shape (Nx - 1,),
    zero on a strip without a spring (``params.foil_springs``, :func:`gfbjax.model.foil.supported_drive`)."""
    return supported_drive(gauge(mean_gauge_pressure(P, grid), params.gumbel_width), params.foil_springs)


def core_rates(s: Array, omega: Array, F_U: Array, params: Params) -> Array:
    """d/dtau of the N core states (pressures, foil strips, rotor), Eq. (17), for a given unbalance forcing."""
    lay = layout(params)
    grid = lay.grid
    P = lay.pressures(s)
    q = lay.foil_deflection(s)
    r = lay.rotor(s)
    theta = grid.theta(params.theta0)
    # foil first: its rate enters dh/dtau of the Reynolds equation
    drive = foil_drive(P, grid, params)
    qdot = foil_rates(q, drive, omega, params.alpha_f, params.eta, params.structural_damping)
    vx, vy = (r[2], r[3]) if params.rotor == "rigid" else (r[4], r[5])
    h = film_thickness(grid.theta_nodes(params.theta0), r[0], r[1], jnp.pad(q, 1))
    hdot = -vx * jnp.cos(theta) - vy * jnp.sin(theta) + qdot
    Pdot = pressure_rates(P, h, hdot, omega, params.kappa, grid)
    if params.gumbel == "pressure":
        Pdot = ambient_clipped_rates(Pdot, P, params.gumbel_width)
    F_B = bearing_force(P, theta, grid, params.gumbel_width, gumbel=True)
    rdot = rotor_rates(r, F_B, F_U, params)
    return jnp.concatenate([Pdot.reshape(-1), qdot, rdot])


def vector_field(s: Array, omega: Array, params: Params) -> Array:
    """Autonomous GFB-rotor system, Eq. (21)-(22): core states + phase oscillator (last two states)."""
    u, v = s[-2], s[-1]
    F_U = unbalance_force(omega, params.eps, u, v)
    return jnp.concatenate([core_rates(s[:-2], omega, F_U, params), oscillator_rates(u, v, omega)])


def balanced_vector_field(s: Array, omega: Array, params: Params) -> Array:
    """Core system without unbalance (balanced rotor, G0): an autonomous system with equilibria."""
    return core_rates(s, omega, jnp.zeros(2, s.dtype), params)


def forced_vector_field(tau: Array, s: Array, omega: Array, params: Params) -> Array:
    """Non-autonomous system at constant speed, Eq. (17) with Eq. (15a): unbalance phase ``Omega tau``."""
    phi = omega * tau
    return core_rates(s, omega, unbalance_force(omega, params.eps, jnp.cos(phi), jnp.sin(phi)), params)


def runup_vector_field(tau: Array, s: Array, params: Params, omega0: Array, accel: Array) -> Array:
    """Run-up (or coast-down, ``accel < 0``) at constant acceleration from ``omega0``, Eq. (15b):
    ``Omega = omega0 + accel tau``, phase ``omega0 tau + accel tau^2 / 2``; the Reynolds equation and the foil
    damping see the instantaneous speed."""
    omega = omega0 + accel * tau
    phi = omega0 * tau + 0.5 * accel * tau**2
    return core_rates(s, omega, unbalance_force_runup(omega, accel, params.eps, phi), params)


def initial_state(params: Params, oscillator: bool = False) -> Array:
    """Ambient pressure, unloaded foil, rotor at rest at the bearing centre with the static shaft sag
    (Eq. 6); oscillator on its cycle at phase 0."""
    lay = layout(params, oscillator)
    grid = lay.grid
    P = jnp.ones((grid.n_theta, grid.n_z))
    q = jnp.zeros(grid.n_theta)
    r = jnp.zeros(lay.n_rotor)
    if params.rotor == "jeffcott":
        r = r.at[3].set(-params.sigma / params.k_s)
    osc = jnp.array([1.0, 0.0]) if oscillator else None
    return lay.pack(P, q, r, osc)


def plain_bearing_rates(P: Array, x: Array, y: Array, vx: Array, vy: Array, omega: Array, kappa: Array,
                        grid: Grid) -> Array:
    """Pressure rates of a plain rigid 360-degree gas journal bearing (periodic in theta, no foil): the
    validation model of docs/model.md.  Journal at (x, y)/c moving at (vx, vy) [c/t*]."""
    theta = grid.theta(0.0)
    h = film_thickness(theta, x, y)
    hdot = -vx * jnp.cos(theta) - vy * jnp.sin(theta)
    return pressure_rates(P, h, hdot, omega, kappa, grid)
