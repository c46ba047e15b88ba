r"""Bifurcations of cycles: test functions, localisation, period-doubling switch.

Test functions along a branch of cycles (trivial multiplier(s) closest to +1
removed first, see ``floquet.nontrivial``):

* **LPC** (fold of cycles): the lam-component of the normalised tangent
  :math:`\dot\lambda` changes sign.
* **PD** (flip): a real multiplier crosses -1.  Detected by a change of the
  number of real multipliers below -1; localised on
  :math:`\psi_{PD} = \prod_{\mu\ real} (\mu + 1) \prod_{\mu\ complex} |\mu + 1|`,
  i.e. :math:`\det(M + I)` over the non-trivial multipliers: continuous, and of
  changing sign both in the generic flip and where a complex pair meets at -1
  and splits into -r, -1/r (Hamiltonian or parametric resonance, e.g. the
  Mathieu tongues), where the multiplier closest to -1 never crosses it.
* **NS** (Neimark-Sacker / torus): a complex pair crosses :math:`|\mu| = 1`.
  Detected by a change of the number of complex multipliers outside the unit
  circle, localised on :math:`\psi_{NS} = |\mu_c| - 1` for the complex
  multiplier closest to the circle; the angle :math:`\arg\mu_c \in (0,\pi)`
  is reported.  Pairs with :math:`|\arg\mu| <` ``NS_MIN_ANGLE`` count as real:
  next to a Hopf point a cycle has a second multiplier near +1, and the nearly
  defective pair it forms with the trivial one splits into a spurious complex
  pair of tiny argument (a 1:1 resonance, not a torus).

Localisation is the driver's (:func:`._driver.locate`).
"""
from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np

from . import _collocation as col
from ._floquet import nontrivial

IMAG_TOL = 1e-7
NS_MIN_ANGLE = 1e-2  # rad


def _is_real(mu: np.ndarray) -> np.ndarray:
    return (np.abs(mu.imag) <= IMAG_TOL * np.maximum(1.0, np.abs(mu))) | (np.abs(np.angle(mu)) < NS_MIN_ANGLE)


def cycle_test_functions(mu: np.ndarray, n_trivial: int, tangent_lam: float) -> dict[str, float]:
    """Counts (n_pd, n_ns) and continuous test functions (LPC, PD, NS)."""
    nt = nontrivial(mu, n_trivial)
    real = _is_real(nt)
    neg = nt[real & (nt.real < 0)].real
    cplx = nt[~real]
    psi_pd = float(np.prod(nt[real].real + 1.0) * np.prod(np.abs(cplx + 1.0)))
    psi_ns = float(np.abs(cplx[np.argmin(np.abs(np.abs(cplx) - 1.0))]) - 1.0) if len(cplx) else -1.0
    return {"LPC": float(tangent_lam), "PD": psi_pd, "NS": psi_ns,
            "n_pd": int(np.sum(neg < -1.0)), "n_ns": int(np.sum(np.abs(cplx) > 1.0))}


def detect(prev: dict[str, float], cur: dict[str, float], kinds: tuple[str, ...]) -> list[str]:
    """Bifurcation types crossed between two consecutive points."""
    out = []
    if "LPC" in kinds and np.sign(prev["LPC"]) * np.sign(cur["LPC"]) < 0:
        out.append("LPC")
    if "PD" in kinds and prev["n_pd"] != cur["n_pd"]:
        out.append("PD")
    if "NS" in kinds and prev["n_ns"] != cur["n_ns"]:
        out.append("NS")
    return out


def ns_angle(mu: np.ndarray, n_trivial: int) -> float:
    """arg of the complex multiplier closest to the unit circle, in (0, pi)."""
    nt = nontrivial(mu, n_trivial)
    cplx = nt[~_is_real(nt)]
    if not len(cplx):
        return float("nan")
    c = cplx[np.argmin(np.abs(np.abs(cplx) - 1.0))]
    return float(abs(np.angle(c)))


def double_orbit_pd(f: Any, args: Any, orbit: col.Orbit, scheme: col.Scheme,
                    G: np.ndarray) -> tuple[col.Orbit, col.Orbit]:
    """Period-doubling branch switch data.

    Returns the orbit traversed twice on the doubled mesh (period 2T, 2N
    intervals) and the normalised direction of the emanating branch:
    the PD eigenfunction v(t) of the variational problem (multiplier -1),
    propagated over [0, T] with the transfer matrices, continued by -v over
    [T, 2T] so that it is 2T-periodic; T and lam components zero.
    """
    G = np.asarray(G)
    N, n = G.shape[0], G.shape[1]
    M = np.eye(n)
    for g in G:
        M = g @ M
    ev, V = np.linalg.eig(M)
    k = int(np.argmin(np.abs(ev + 1.0)))
    v0 = np.real(V[:, k])
    v0 /= np.linalg.norm(v0)
    vs = [v0]
    for g in G:
        vs.append(g @ vs[-1])
    vm = np.array(vs)  # (N+1, n), vm[N] ~ -v0
    vi = np.asarray(col.interior_response(f, args, orbit, scheme, jnp.asarray(vm)))
    mesh = np.asarray(orbit.mesh)
    mesh2 = np.concatenate([0.5 * mesh, 0.5 + 0.5 * mesh[1:]])
    xm, xi = np.asarray(orbit.xm), np.asarray(orbit.xi)
    doubled = col.Orbit(jnp.asarray(mesh2), jnp.asarray(np.concatenate([xm, xm[1:]])),
                        jnp.asarray(np.concatenate([xi, xi])), 2.0 * orbit.T, orbit.lam)
    dm = np.concatenate([vm, -vm[1:]])
    dm[-1] = dm[0]
    direction = col.Orbit(doubled.mesh, jnp.asarray(dm), jnp.asarray(np.concatenate([vi, -vi])),
                          jnp.asarray(0.0), jnp.asarray(0.0))
    nrm = float(jnp.sqrt(col.inner(direction, direction, scheme)))
    return doubled, direction.scale(1.0 / nrm)
