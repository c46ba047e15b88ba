"""Finite-difference grid of the gas film and the layout of the state vector.

The film is discretised on the half domain (symmetry, paper Eq. 5):

* circumferential nodes ``theta_i = theta0 + i * dtheta``, ``dtheta = 2 pi / Nx``, ``i = 0..Nx``.  For the foil
  bearing ``p = 1`` at the foil's fixed end, ``i = 0`` and ``i = Nx`` (Eq. 4), so the unknowns are ``i = 1..Nx-1``.
  For the plain 360-degree bearing the grid is periodic and the unknowns are ``i = 0..Nx-1``;
* axial nodes ``z_j = j * dz``, ``dz = 1 / (2 Nz)`` (z over the bearing length L), ``j = 0..Nz``: ``p = 1`` at the
  edge ``j = 0``; ``j = Nz`` is the mid-plane, where ``dp/dz = 0`` is imposed with a mirror node
  ``p_{Nz+1} = p_{Nz-1}`` (second order; the paper's one-sided Eq. 5 is first order).  Unknowns ``j = 1..Nz``.
  With ``full_length`` (``SystemSpec.axial_domain = "full"``) the whole length is solved at the same spacing:
  ``j = 0..2 Nz``, ``p = 1`` at both edges, unknowns ``j = 1..2 Nz - 1`` and no symmetry condition; for an aligned
  journal its symmetric solution satisfies the half domain's equations node for node.

State vector of the GFB-rotor system (both bearings carry identical films by symmetry, so one film is stored)::

    s = [ p (n_theta * n_z, row-major: theta index slow) | q (n_theta foil strips) | rotor | oscillator (2) ]

rotor = ``[x_j, y_j, x_d, y_d, x_j', y_j', x_d', y_d']`` for the Jeffcott rotor (Eq. 12) and ``[x_j, y_j, x_j', y_j']``
for the rigid rotor; primes are d/dtau.  The oscillator of Eq. (19) is present only in the autonomous form.
"""

from __future__ import annotations

import math

import equinox as eqx
import jax.numpy as jnp
from jax import Array

__all__ = ["Grid", "StateLayout"]


class Grid(eqx.Module):
    """Geometry of the finite-difference grid (all static).  ``Nz`` counts the intervals over the half length;
    ``full_length`` solves both halves (``n_z = 2 Nz - 1`` axial unknowns instead of ``Nz``)."""

    Nx: int = eqx.field(static=True)
    Nz: int = eqx.field(static=True)
    periodic: bool = eqx.field(static=True, default=False)
    full_length: bool = eqx.field(static=True, default=False)

    @property
    def dtheta(self) -> float:
        return 2.0 * math.pi / self.Nx

    @property
    def dz(self) -> float:
        return 0.5 / self.Nz

    @property
    def n_theta(self) -> int:
        """Number of circumferential unknowns (= number of foil strips for the foil bearing)."""
        return self.Nx if self.periodic else self.Nx - 1

    @property
    def n_z(self) -> int:
        """Number of axial unknowns: ``Nz`` (half domain, mid-plane included) or ``2 Nz - 1`` (full length)."""
        return 2 * self.Nz - 1 if self.full_length else self.Nz

    @property
    def length_factor(self) -> float:
        """Ratio of the bearing length to the solved length: 2 for the half domain, 1 for the full length."""
        return 1.0 if self.full_length else 2.0

    @property
    def n_pressure(self) -> int:
        return self.n_theta * self.n_z

    def theta(self, theta0: float | Array = 0.0) -> Array:
        """Angles of the circumferential unknowns [rad]."""
        i = jnp.arange(self.n_theta) + (0 if self.periodic else 1)
        return theta0 + i * self.dtheta

    def theta_nodes(self, theta0: float | Array = 0.0) -> Array:
        """All circumferential nodes including the foil ends (``Nx + 1`` values; periodic: ``Nx``)."""
        n = self.Nx if self.periodic else self.Nx + 1
        return theta0 + jnp.arange(n) * self.dtheta

    def z(self) -> Array:
        """Axial positions of the unknowns, as a fraction of the bearing length (edge 0, mid-plane 1/2)."""
        return jnp.arange(1, self.n_z + 1) * self.dz

    def z_nodes(self) -> Array:
        """Axial positions of every node of :meth:`full_field`: edge 0 to the mid-plane 1/2 (full length: to 1)."""
        return jnp.arange(self.n_z + (2 if self.full_length else 1)) * self.dz

    def z_weights(self) -> Array:
        """Trapezoid weights of the unknowns over the solved length (the edge nodes, p = 1, carry none; the
        half domain's mid-plane node carries half a cell)."""
        w = jnp.full((self.n_z,), self.dz)
        return w if self.full_length else w.at[-1].set(0.5 * self.dz)

    def full_field(self, P: Array) -> Array:
        """The pressure on all nodes, boundaries included: shape (Nx+1, n_z+1) (periodic: (Nx, n_z+1); full
        length: one more column, the second edge)."""
        edge = jnp.ones((P.shape[0], 1), P.dtype)
        P = jnp.concatenate([edge, P, edge] if self.full_length else [edge, P], axis=1)
        if self.periodic:
            return P
        one = jnp.ones((1, P.shape[1]), P.dtype)
        return jnp.concatenate([one, P, one], axis=0)


class StateLayout(eqx.Module):
    """Where each part of the state lives; named views return reshaped slices (jit-safe)."""

    grid: Grid
    n_rotor: int = eqx.field(static=True)
    oscillator: bool = eqx.field(static=True)
    foil: bool = eqx.field(static=True, default=True)

    @property
    def n_foil(self) -> int:
        return self.grid.n_theta if self.foil else 0

    @property
    def n_core(self) -> int:
        """Size N of the non-autonomous system, Eq. (17)."""
        return self.grid.n_pressure + self.n_foil + self.n_rotor

    @property
    def n(self) -> int:
        """Total number of states."""
        return self.n_core + (2 if self.oscillator else 0)

    @property
    def slices(self) -> dict[str, slice]:
        g = self.grid
        a = g.n_pressure
        b = a + self.n_foil
        c = b + self.n_rotor
        return {"pressures": slice(0, a), "foil": slice(a, b), "rotor": slice(b, c), "oscillator": slice(c, self.n)}

    def pressures(self, s: Array) -> Array:
        """Pressure unknowns ``p/p0`` as an (n_theta, n_z) array."""
        return s[..., : self.grid.n_pressure].reshape(s.shape[:-1] + (self.grid.n_theta, self.grid.n_z))

    def foil_deflection(self, s: Array) -> Array:
        """Foil strip deflections ``q/c``, one per circumferential unknown."""
        return s[..., self.slices["foil"]]

    def rotor(self, s: Array) -> Array:
        """Rotor positions and velocities (see module docstring for the order)."""
        return s[..., self.slices["rotor"]]

    def oscillator_state(self, s: Array) -> Array:
        """The two oscillator states of Eq. (19) (cos and sin of the unbalance phase on the cycle)."""
        return s[..., self.slices["oscillator"]]

    def journal(self, s: Array) -> Array:
        """Journal centre ``(x_j, y_j)/c``."""
        return self.rotor(s)[..., :2]

    def pack(self, P: Array, q: Array | None, rotor: Array, osc: Array | None = None) -> Array:
        parts = [jnp.reshape(P, (-1,))]
        if self.foil:
            parts.append(q)
        parts.append(rotor)
        if self.oscillator:
            parts.append(osc)
        return jnp.concatenate(parts)
