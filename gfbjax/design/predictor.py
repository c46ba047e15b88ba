r"""Predictor of the optimised continuation in speed (issue 15, item 3): where the next speed's optimum and its
cycle will be, from the optima already found.

The optimum ``z*(Omega) = log x*(Omega)`` of a smooth objective with a non-degenerate minimum is a smooth curve
(the optimality conditions ``g(z*, Omega) = 0`` and the implicit function theorem: ``H dz*/dOmega =
-dg/dOmega``).  A polynomial through the last optima (:func:`extrapolate`) is the finite-difference form of that
sensitivity at no cost in cycle solves: order 1 (secant) is the first-order KKT tangent, order 2 adds its
curvature.  A variable on a bound at the last optimum stays there (an active bound usually stays active over a
speed step).  The cycle at the predicted foil is extrapolated with the same weights (:func:`extrapolate_orbit`),
since the foil and the cycle move together along the schedule.

:class:`OptimumTrail` keeps the last optima (speed, z, cycle) and the optimiser's curvature model, the state that
:func:`gfbjax.design.schedule.optimized_continuation` carries from speed to speed.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..cont import Orbit

__all__ = ["lagrange_weights", "extrapolate", "extrapolate_orbit", "OptimumTrail"]


def lagrange_weights(nodes: np.ndarray, t: float) -> np.ndarray:
    """Weights ``w`` with ``p(t) = sum_i w_i p(nodes_i)`` for the polynomial of degree ``len(nodes) - 1`` through
    the nodes.  nodes: shape (k,), distinct (ValueError otherwise)."""
    nodes = np.asarray(nodes, float).reshape(-1)
    if len(np.unique(nodes)) != nodes.size:
        raise ValueError(f"the nodes must be distinct, got {nodes.tolist()}")
    w = np.ones(nodes.size)
    for i in range(nodes.size):
        for j in range(nodes.size):
            if j != i:
                w[i] *= (t - nodes[j]) / (nodes[i] - nodes[j])
    return w


def extrapolate(omegas: np.ndarray, zs: np.ndarray, omega_next: float, zl: np.ndarray, zh: np.ndarray, *,
                order: int = 2, max_move: float | None = 1.0) -> np.ndarray:
    """Predict the optimum at ``omega_next`` from the last optima, in log variables.

    The polynomial of degree ``min(order, k - 1)`` through the last k optima since the last jump (a move of more
    than ``max_move`` between consecutive optima: the optimum went over to another local minimum, and a
    polynomial through both means nothing); a variable on a bound at the last optimum (within 1e-9 of the log
    range) is kept there; the move from the last optimum is capped at ``max_move`` (infinity norm, log units;
    None: no cap, no jumps); the result is clipped onto the box.

    Args:
        omegas: speeds of the optima (Omega_bar), shape (k,), k >= 1, distinct.
        zs: optima ``log x*``, shape (k, d).
        omega_next: the speed to predict for.
        zl, zh: log bounds, shape (d,).
        order: highest polynomial degree, >= 0.
        max_move: cap on the predicted move, > 0, or None.

    Returns:
        predicted ``log x*(omega_next)``, shape (d,).
    """
    omegas = np.asarray(omegas, float).reshape(-1)
    zs = np.asarray(zs, float).reshape(omegas.size, -1)
    if omegas.size == 0:
        raise ValueError("extrapolate needs at least one optimum")
    if order < 0:
        raise ValueError(f"order must be >= 0, got {order}")
    zl, zh = np.asarray(zl, float), np.asarray(zh, float)
    k = min(order + 1, omegas.size)
    if max_move is not None:
        for i in range(1, k):  # stop at the first jump, going back from the last optimum
            if np.max(np.abs(zs[-i] - zs[-i - 1])) > max_move:
                k = i
                break
    z_last = zs[-1]
    pred = lagrange_weights(omegas[-k:], omega_next) @ zs[-k:]
    tol = 1e-9 * (zh - zl)
    on_bound = (z_last <= zl + tol) | (z_last >= zh - tol)
    pred = np.where(on_bound, z_last, pred)
    move = np.max(np.abs(pred - z_last)) if pred.size else 0.0
    if max_move is not None and move > max_move:
        pred = z_last + (pred - z_last) * (max_move / move)
    return np.clip(pred, zl, zh)


def extrapolate_orbit(omegas: np.ndarray, orbits: list[Orbit], omega_next: float, order: int = 1) -> Orbit:
    """The cycle predicted at ``omega_next``: a polynomial of degree up to ``order`` through the node values of the
    last cycles (the caller passes those since the last jump of the optimum; shape-compatible orbits on the same
    mesh, otherwise the last one is returned unchanged).
    Period and parameter are those of the last orbit; :meth:`gfbjax.design.evaluate.FoilDesign.set_speed` sets
    them for the new speed."""
    k = min(order + 1, len(orbits))
    last = orbits[-1]
    recent = orbits[-k:]
    if k < 2 or any(o.xm.shape != last.xm.shape or o.xi.shape != last.xi.shape
                    or not np.array_equal(np.asarray(o.mesh), np.asarray(last.mesh)) for o in recent):
        return last
    w = lagrange_weights(np.asarray(omegas, float)[-k:], omega_next)
    xm = sum(wi * o.xm for wi, o in zip(w, recent))
    xi = sum(wi * o.xi for wi, o in zip(w, recent))
    return Orbit(last.mesh, xm, xi, last.T, last.lam)


@dataclass
class OptimumTrail:
    """The optima so far along the schedule (speed, ``z = log x*``, cycle; the last ``keep`` of them) and the
    optimiser's curvature model at the last one (shape (d, d) or None), with the bounds in log variables.

    :meth:`predict` gives the next start point and cycle; :meth:`add` records an optimum.  ``order`` and
    ``max_move`` go to :func:`extrapolate`."""

    zl: np.ndarray
    zh: np.ndarray
    order: int = 1
    max_move: float | None = 1.0
    keep: int = 3
    omegas: list[float] = field(default_factory=list)
    zs: list[np.ndarray] = field(default_factory=list)
    orbits: list[Orbit] = field(default_factory=list)
    hessian: np.ndarray | None = None

    def add(self, omega: float, x: np.ndarray, orbit: Orbit | None, hessian: np.ndarray | None) -> None:
        """Record the optimum ``x`` (physical variables, shape (d,)) at ``omega`` with its cycle and the final
        curvature model (None keeps the previous model)."""
        self.omegas = (self.omegas + [float(omega)])[-self.keep:]
        self.zs = (self.zs + [np.log(np.asarray(x, float))])[-self.keep:]
        if orbit is not None:
            self.orbits = (self.orbits + [orbit])[-self.keep:]
        if hessian is not None:
            self.hessian = np.array(hessian, float)

    def predict(self, omega: float) -> tuple[np.ndarray, Orbit | None]:
        """Predicted optimum (physical variables, shape (d,)) and cycle at ``omega`` (None: nothing recorded)."""
        if not self.omegas:
            raise ValueError("no optimum recorded yet")
        z = extrapolate(np.array(self.omegas), np.array(self.zs), omega, self.zl, self.zh, order=self.order,
                        max_move=self.max_move)
        x = np.clip(np.exp(z), np.exp(self.zl), np.exp(self.zh))
        if len(self.orbits) != len(self.omegas):  # a cycle is missing: the extrapolation would mix speeds
            return x, (self.orbits[-1] if self.orbits else None)
        k = len(self.omegas)  # the cycles since the last jump of the optimum, as for the foil
        if self.max_move is not None:
            zs = np.array(self.zs)
            jumps = [i for i in range(1, k) if np.max(np.abs(zs[i] - zs[i - 1])) > self.max_move]
            k -= jumps[-1] if jumps else 0
        return x, extrapolate_orbit(np.array(self.omegas[-k:]), self.orbits[-k:], omega, self.order)
