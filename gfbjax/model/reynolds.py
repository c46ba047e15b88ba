"""Compressible Reynolds equation on the finite-difference grid: pressure rates (Eq. 2b, as corrected in
docs/model.md), film thickness (Eq. 3), bearing forces (Eq. 7) and strip mean pressure (Eq. 9).

All quantities are dimensionless: ``p = p/p0``, ``h = h/c``, time ``tau = t/t*``, speed ``Omega_bar`` (= the
bearing number Lambda).  The discretisation is conservative and second order: Poiseuille fluxes on cell faces with
the face coefficient ``p h^3`` averaged from the two nodes, and a central difference for the Couette term.

Two model options of :class:`gfbjax.SystemSpec` act here (docs/model.md):

* ``axial_domain``: the half length with a mid-plane symmetry condition (default) or the full length with ambient
  pressure at both edges (:class:`Grid` ``full_length``);
* ``gumbel``: the Gumbel condition on the bearing force and the foil drive only (``"forces"``, default) or on the
  film pressure itself (``"pressure"``, :func:`ambient_clipped_rates`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array

from .grid import Grid

__all__ = ["gauge", "film_thickness", "pressure_rates", "ambient_clipped_rates", "bearing_force",
           "mean_gauge_pressure", "GUMBEL", "AMBIENT_RELAXATION"]

#: Where the Gumbel condition acts (:attr:`gfbjax.SystemSpec.gumbel`): on the bearing force and the foil drive only,
#: or on the film pressure itself.
GUMBEL = ("forces", "pressure")
#: Rate [1/tau] at which ``gumbel="pressure"`` returns a node below ambient to ambient.  It is the eigenvalue
#: (-rate) of every clipped node and moves no other eigenvalue (their Jacobian rows hold only the diagonal), so it
#: does not change equilibria or their stability; 1 is of the order of the film's own rates at Omega_bar ~ 1.
AMBIENT_RELAXATION = 1.0


def gauge(x: Array, width: float = 0.0) -> Array:
    """Gumbel's condition ``max(x, 0)`` for a gauge pressure x; with ``width > 0`` the smooth
    ``width * softplus(x / width)`` (exceeds max(x, 0) by at most ``width * ln 2``, at x = 0)."""
    if width == 0.0:
        return jnp.maximum(x, 0.0)
    return width * jax.nn.softplus(x / width)


def film_thickness(theta: Array, x: Array, y: Array, q: Array | float = 0.0) -> Array:
    """Film thickness ``h = 1 - x cos(theta) - y sin(theta) + q``, Eq. (3), for a journal at (x, y)/c."""
    return 1.0 - x * jnp.cos(theta) - y * jnp.sin(theta) + q


def _pad(P: Array, h: Array, grid: Grid) -> tuple[Array, Array]:
    """Pressure with boundary and mirror nodes: theta (ends p=1 or periodic), z (edge p=1, mid-plane mirror; full
    length: p=1 at both edges).

    ``h`` must already include the end nodes for the foil bearing (length Nx+1) or be periodic (length Nx).
    Returns the padded pressure (n_theta+2, n_z+2) and film (n_theta+2,) with one neighbour on each side.
    """
    ones = jnp.ones((P.shape[0], 1), P.dtype)
    if grid.full_length:
        Pz = jnp.concatenate([ones, P, ones], axis=1)
    else:
        Pz = jnp.concatenate([ones, P, P[:, -2:-1]], axis=1)  # edge j=0, unknowns 1..Nz, mirror of Nz-1
    if grid.periodic:
        Pp = jnp.concatenate([Pz[-1:], Pz, Pz[:1]], axis=0)
        hp = jnp.concatenate([h[-1:], h, h[:1]])
    else:
        row = jnp.ones((1, Pz.shape[1]), P.dtype)
        Pp = jnp.concatenate([row, Pz, row], axis=0)
        hp = h
    return Pp, hp


def pressure_rates(P: Array, h: Array, hdot: Array, omega: Array, kappa: Array, grid: Grid) -> Array:
    """dp/dtau at the unknowns, Eq. (2b) (corrected, docs/model.md):

    ``p' = [ 1/2 d/dth(p h^3 dp/dth) + kappa^2/2 d/dz(p h^3 dp/dz) - Omega/2 d/dth(p h) ] / h - p h'/h``.

    Args:
        P: pressures at the unknowns, shape (n_theta, n_z) (``n_z = Nz``, or ``2 Nz - 1`` on the full length).
        h: film thickness at all circumferential nodes: (Nx+1,) for the foil bearing (ends included),
            (Nx,) for the periodic bearing.
        hdot: dh/dtau at the unknowns, shape (n_theta,).
        omega: speed Omega_bar.
        kappa: R / L.
        grid: the grid.
    """
    Pp, hp = _pad(P, h, grid)
    dth, dz = grid.dtheta, grid.dz
    h3 = hp[:, None] ** 3
    a = Pp * h3  # p h^3 at every padded node
    # circumferential Poiseuille flux on faces i+1/2, then its divergence at the unknowns
    a_face = 0.5 * (a[1:, 1:-1] + a[:-1, 1:-1])
    flux_t = a_face * (Pp[1:, 1:-1] - Pp[:-1, 1:-1]) / dth
    div_t = (flux_t[1:] - flux_t[:-1]) / dth
    # axial flux on faces j+1/2 (h does not vary along z)
    az_face = 0.5 * (a[1:-1, 1:] + a[1:-1, :-1])
    flux_z = az_face * (Pp[1:-1, 1:] - Pp[1:-1, :-1]) / dz
    div_z = (flux_z[:, 1:] - flux_z[:, :-1]) / dz
    # Couette term, central difference of p h
    ph = Pp[:, 1:-1] * hp[:, None]
    conv = (ph[2:] - ph[:-2]) / (2.0 * dth)
    hc = hp[1:-1, None]
    return (0.5 * div_t + 0.5 * kappa**2 * div_z - 0.5 * omega * conv) / hc - P * hdot[:, None] / hc


def ambient_clipped_rates(Pdot: Array, P: Array, width: float = 0.0, rate: float = AMBIENT_RELAXATION) -> Array:
    """The Gumbel condition applied to the film pressure itself (``SystemSpec.gumbel = "pressure"``; paper
    Sect. 2.1: a pressure below ambient "should be considered equal to p0").

    ``p' = Pdot`` above ambient (the Reynolds equation untouched, so transients and cycles above ambient are the
    model's own), ``p' = max(Pdot, rate (1 - p))`` at or below it: a node at ambient whose Reynolds rate ``Pdot`` is
    negative stays at ambient, a node below ambient returns to it at ``rate``.  Its equilibria are those of the
    Reynolds equation with the complementarity ``p >= 1``, ``Pdot <= 0``, ``(p - 1) Pdot = 0`` (the Swift-Stieber condition that clipping the
    pressure in an iterative Reynolds solver converges to), so a steady film never drops below ambient.

    Args:
        Pdot: Reynolds rates :func:`pressure_rates` at the unknowns, any shape.
        P: pressures over p0 at the same unknowns.
        width: smoothing of the ``max`` at or below ambient (:func:`gauge`); 0 = exact.
        rate: relaxation rate [1/tau] below ambient, > 0 (:data:`AMBIENT_RELAXATION`).
    """
    floor = rate * (1.0 - P)
    # above ambient the floor would cap how fast a pressure may fall (at rate (p - 1)): not part of the condition
    return jnp.where(P > 1.0, Pdot, floor + gauge(Pdot - floor, width))


def bearing_force(P: Array, theta: Array, grid: Grid, width: float = 0.0, gumbel: bool = True) -> Array:
    """Gas force on the journal over the whole bearing length, Eq. (7), in units of ``p0 R L``.

    ``F = -int_0^2pi int_0^1 g(p - 1) (cos th, sin th) dz dth`` with g the Gumbel ``max(., 0)`` (or the identity
    when ``gumbel`` is False, for the plain bearing).  Trapezoid rule; the half domain counts twice.
    """
    gp = gauge(P - 1.0, width) if gumbel else P - 1.0
    col = grid.length_factor * gp @ grid.z_weights()  # integral over the full length, per circumferential node
    w = grid.dtheta * col
    return -jnp.stack([jnp.sum(w * jnp.cos(theta)), jnp.sum(w * jnp.sin(theta))])


def mean_gauge_pressure(P: Array, grid: Grid) -> Array:
    """Strip mean gauge pressure ``p_m - 1`` over the bearing length, Eq. (9), trapezoid rule."""
    return grid.length_factor * (P - 1.0) @ grid.z_weights()
