r"""Bifurcations of cycles: continuous test functions, their classification, the period-doubling switch.

Test functions along a branch of cycles, on the non-trivial multipliers (the ``n_trivial`` closest to +1 removed,
see ``_floquet.nontrivial``); each is a continuous function of the multipliers whose sign changes at the event,
so that crossings are found whatever else is already unstable, and nothing is inferred from counting multipliers
on one side of a line:

* **LPC** (fold of cycles): the lam-component of the unit tangent :math:`\dot\lambda`.
* **PD** (flip): the sign of :math:`\prod_i (\mu_i + 1)/(|\mu_i| + 1)`, i.e. of :math:`\det(M + I)` over the
  non-trivial multipliers, times its two smallest factors (:func:`signed_min`: continuous, no underflow for
  many multipliers).  Its sign changes when a real multiplier crosses -1, and where a complex pair meets at -1 and
  splits into -r, -1/r (parametric resonance, e.g. the Mathieu tongues).  Two real multipliers below -1 that
  merge into a complex pair (or the reverse) leave it unchanged: no PD.
* **BPC** (branch point of cycles): the same for :math:`\det(I - M)` over the non-trivial multipliers; its sign
  changes when a real multiplier passes through +1.  At a fold of cycles a multiplier passes through +1 too, so a
  step in which the LPC test also changes sign reports the fold only (:func:`detect`).
* **NS** (Neimark-Sacker / torus): the same for :math:`\prod_{i<j} (1 - \mu_i\mu_j)/(|\mu_i\mu_j| + 1)` over
  the non-trivial pairs (the bialternate product of M): zero when a complex pair crosses the unit circle
  (:math:`\mu\bar\mu = 1`), unchanged when multipliers collide on the real axis.  It also vanishes for two real
  multipliers with product 1 (a neutral saddle, not a bifurcation): :func:`classify` reports an NS only when the
  pair with product closest to 1 is complex, with its angle :math:`\arg\mu \in (0, \pi)`.

Every factor is oriented to be positive for a multiplier (or pair) well inside the unit circle: (1 + mu),
(1 - mu), (1 - mu_i mu_j).  With a partial spectrum (the k leading multipliers of :class:`~._floquet.BlockKrylov`) the
smallest computed multiplier enters and leaves the set as the spectrum moves; with the other orientation each such
change flipped the sign of the product, and a spurious BPC or NS was reported where nothing crossed the circle.

The set of non-trivial multipliers is made closed under conjugation first: next to a Hopf point the trivial
multiplier and the amplitude multiplier form a nearly defective pair that round-off can split into
:math:`1 \pm i\epsilon`; removing one of them leaves a lone complex value, which is replaced by a real one of the
same modulus (a 1:1 resonance, not a torus).

Localisation is the driver's (:func:`._localise.locate`).
"""
from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from scipy.optimize import linear_sum_assignment

from . import _collocation as col
from ._floquet import nontrivial

IMAG_TOL = 1e-7  # relative imaginary part below which a multiplier is real
#: distance from the stability boundary (relative) at which an eigenvalue or multiplier counts as on it: a point
#: exactly on an event, where the unstable count cannot say on which side the crossing member is
ON_BOUNDARY = 1e-13


def _outside(z: np.ndarray) -> np.ndarray:
    """Unstable multipliers: outside the unit circle."""
    return np.abs(z) > 1.0


def _from_circle(z: np.ndarray) -> np.ndarray:
    """Distance of multipliers from the unit circle."""
    return np.abs(np.abs(z) - 1.0)


def _conjugate_closed(nt: np.ndarray) -> np.ndarray:
    """``nt`` with every complex value whose conjugate is missing replaced by a real one of the same modulus."""
    nt = np.asarray(nt, complex).copy()
    scale = np.maximum(1.0, np.abs(nt))
    for i, z in enumerate(nt):
        if abs(z.imag) > IMAG_TOL * scale[i] and not np.any(np.abs(nt - np.conj(z)) <= 1e-8 * scale[i]):
            nt[i] = np.sign(z.real or 1.0) * abs(z)
    return nt


def _pair_products(nt: np.ndarray) -> np.ndarray:
    i, j = np.triu_indices(len(nt), 1)
    return nt[i] * nt[j]


def signed_min(factors: np.ndarray) -> float:
    """A continuous stand-in for the real product of ``factors`` (a set closed under conjugation, each of modulus
    about 1 or less): its sign times the product of the two smallest moduli.  The product of thousands of factors
    underflows, and its magnitude says nothing near a root; the sign (from the sum of the arguments) flips exactly
    when a factor passes through zero, and the two smallest moduli are continuous there.  Two, because a complex
    pair whose product is the event (two multipliers meeting at -1 and splitting on the real axis, as in the
    Mathieu tongues) contributes two factors that vanish together like the square root of the parameter: their
    product is then linear in it, as the full product is."""
    f = np.asarray(factors, complex)
    if f.size == 0:
        return 1.0
    sign = 1.0 if np.cos(np.sum(np.angle(f))) >= 0.0 else -1.0
    return sign * float(np.prod(np.sort(np.abs(f))[:2]))


def cycle_test_functions(mu: np.ndarray, n_trivial: int, tangent_lam: float) -> dict[str, float]:
    """The continuous test functions LPC, PD, BPC and NS of one point (module docstring), and ``UNSTABLE``, the
    number of non-trivial multipliers outside the unit circle, ``BOUNDARY``, the number on it, and ``CRITICAL``,
    the multipliers nearest the circle (not test functions: the driver compares the crossings over a step with
    the events found)."""
    nt = _conjugate_closed(nontrivial(mu, n_trivial))
    pp = _pair_products(nt)
    return {"LPC": float(tangent_lam),
            "PD": signed_min((nt + 1.0) / (np.abs(nt) + 1.0)),
            "BPC": signed_min((1.0 - nt) / (np.abs(nt) + 1.0)),
            "NS": signed_min((1.0 - pp) / (np.abs(pp) + 1.0)),
            "UNSTABLE": float(np.sum(_outside(nt))),
            "BOUNDARY": float(np.sum(_from_circle(nt) <= ON_BOUNDARY)),
            "CRITICAL": critical(nt, _from_circle)}


def multiplier_crossings(before: np.ndarray, after: np.ndarray) -> int:
    """:func:`matched_crossings` for multipliers (unstable: outside the unit circle)."""
    return len(crossed_multipliers(before, after))


def crossed_multipliers(before: np.ndarray, after: np.ndarray) -> list[int]:
    """:func:`crossed_members` for multipliers (unstable: outside the unit circle)."""
    return crossed_members(before, after, _outside, _from_circle)


#: How many multipliers cross the unit circle at each event (for the driver's check that a step's sign changes
#: account for every crossing: two crossings in one step cancel in a test function).
EVENT_WEIGHTS = {"LPC": 1, "PD": 1, "BPC": 1, "NS": 2}


def side(value: float) -> int:
    """The side of zero a test value lies on, zero counted with the positive side: a point that lands exactly on
    an event (a test value of exactly 0.0, as on a parameter grid aligned with the event) then belongs to one
    side, so the crossing is found once, in the step that reaches the zero or in the one that leaves it (with the
    plain sign, 0 * anything is no change on either step and the event was lost)."""
    return 1 if value >= 0.0 else -1


def sign_changes(prev: dict[str, float], cur: dict[str, float], kinds: tuple[str, ...]) -> list[str]:
    """The test functions among ``kinds`` that changed :func:`side` between two consecutive points (both finite)."""
    return [k for k in kinds if np.isfinite(prev[k]) and np.isfinite(cur[k]) and side(prev[k]) != side(cur[k])]


def detect(prev: dict[str, float], cur: dict[str, float], kinds: tuple[str, ...]) -> list[str]:
    """The test functions among ``kinds`` whose sign changed between two consecutive points (a BPC change in the
    same step as an LPC one is the fold's own multiplier through +1: the fold only)."""
    found = sign_changes(prev, cur, kinds)
    if "BPC" in found and "LPC" in found:
        found.remove("BPC")
    return found


#: how many eigenvalues (multipliers) nearest the stability boundary each point keeps for matching (test key
#: "CRITICAL"): enough for every member that can cross within one step
N_CRITICAL = 16


def critical(values: np.ndarray, distance) -> np.ndarray:
    """The :data:`N_CRITICAL` members of ``values`` nearest the stability boundary (``distance(values)``, an
    array), as complex numbers, nearest first."""
    z = np.asarray(values, complex)
    return z[np.argsort(distance(z), kind="stable")[:N_CRITICAL]]


def matched_crossings(before: np.ndarray, after: np.ndarray, unstable, distance) -> int:
    """How many members of the spectrum changed side between two points (:func:`crossed_members`)."""
    return len(crossed_members(before, after, unstable, distance))


def _matches(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest neighbours from ``a`` to ``b`` (index into ``b`` for each member of ``a``) and whether each match
    is confident: the two are each other's nearest, nearer than half the distance to any other candidate."""
    d = np.abs(a[:, None] - b[None, :])
    ab, ba = np.argmin(d, axis=1), np.argmin(d, axis=0)
    second_a = np.sort(d, axis=1)[:, 1] if b.size > 1 else np.full(a.size, np.inf)
    second_b = np.sort(d, axis=0)[1, :] if a.size > 1 else np.full(b.size, np.inf)
    rows = np.arange(a.size)
    confident = (ba[ab] == rows) & (d[rows, ab] < 0.5 * np.minimum(second_a, second_b[ab]))
    return ab, confident


def crossed_members(before: np.ndarray, after: np.ndarray, unstable, distance) -> list[int]:
    """Indices into ``after`` of the members of the spectrum that changed side between two points, followed by
    nearest neighbours. A member counts when it and its nearest neighbour at the other point are a confident
    match (:func:`_matches`), lie on different sides (``unstable(z)``, boolean array), and neither lies on the
    boundary (``distance(z)`` <= :data:`ON_BOUNDARY`: a point exactly on an event, whose crossing belongs to the
    step its test value's side gives). Catches what the unstable count cannot: a pair leaving the stable side while
    another enters in the same step (the count and every test function's sign are then unchanged). Members without
    a confident match are not counted: a wrong match would report a crossing that did not happen
    (:func:`untracked` says when that can hide one)."""
    a, b = np.asarray(before, complex), np.asarray(after, complex)
    if a.size == 0 or b.size == 0:
        return []
    ab, confident = _matches(a, b)
    ua, ub = unstable(a), unstable(b)
    on_a, on_b = distance(a) <= ON_BOUNDARY, distance(b) <= ON_BOUNDARY
    return [int(j) for i, j in enumerate(ab) if confident[i] and ua[i] != ub[j] and not (on_a[i] or on_b[j])]


#: distance from the stability boundary (relative) within which a member's side is taken as unknown when judging
#: whether a step's spectrum was tracked: a conservative system's multipliers lie on the unit circle to the
#: discretisation's accuracy, on either side of it by chance
SIDE_NOISE = 1e-6


def untracked(before: np.ndarray, after: np.ndarray, unstable, distance, metric=None) -> bool:
    """Whether the step between two points may hide a member leaving the stable side while another enters, which
    neither the unstable count nor any test function's sign shows (both cancel) and matching cannot see (the
    spectrum moved too far in the step, e.g. a pair from modulus 0.79 to 9.8 while another, at another angle, went
    from 1.56 to 0.74).  A shorter step tells.

    The members that :func:`crossed_members` cannot match confidently, and whose side is known at both points
    (beyond :data:`SIDE_NOISE`), are paired by the least total distance (``metric(a, b)``, a matrix; default
    ``|a - b|``).  A hidden swap needs a crossing against the net change of the unstable count among them (any
    crossing when the count is unchanged).  The step is untracked when the cheapest pairing has one, or when the
    cheapest pairing with one costs less extra than the two members it moves had moved in the cheapest pairing
    without: the two readings are then too close to call.  A spectrum that moves fast but keeps its order (a real
    pair mu, 1/mu of a Mathieu tongue from -3, -0.33 to -5, -0.2) is tracked.  Not seen: a swap whose member was
    matched confidently to the wrong partner (0.8 to 0.7 while 1.6 went to 10 and 0.8 in fact to 10)."""
    a, b = np.asarray(before, complex), np.asarray(after, complex)
    if a.size == 0 or b.size == 0:
        return False
    ab, confident = _matches(a, b)
    matched_b = np.zeros(b.size, bool)
    matched_b[ab[confident]] = True
    a, b = a[~confident & (distance(a) > SIDE_NOISE)], b[~matched_b & (distance(b) > SIDE_NOISE)]
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    ua, ub = unstable(a), unstable(b)
    if not (ua.any() and (~ua).any() or ub.any() and (~ub).any()):
        return False  # every loose member on one side at each point: no swap between them
    cost = np.abs(a[:, None] - b[None, :]) if metric is None else metric(a, b)
    # the count's own change forces crossings in its direction, which the driver already sees
    net = int(ub.sum()) - int(ua.sum())
    against = (ua[:, None] & ~ub[None, :]) if net > 0 else (~ua[:, None] & ub[None, :]) if net < 0 else \
        (ua[:, None] != ub[None, :])
    staying, rows, cols = _assignment(np.where(against, np.inf, cost))
    if _assignment(cost)[0] < staying:
        return True
    moved_a = np.zeros(a.size)  # each member's distance in the pairing without such a crossing
    moved_a[rows] = cost[rows, cols]
    partner_of_b = np.full(b.size, -1)
    partner_of_b[cols] = rows
    for i, j in zip(*np.nonzero(against)):
        # the cheapest reading with member i going to j, the rest paired freely
        crossed = cost[i, j] + _assignment(np.delete(np.delete(cost, i, 0), j, 1))[0]
        if crossed - staying < moved_a[i] + (moved_a[partner_of_b[j]] if partner_of_b[j] >= 0 else 0.0):
            return True
    return False


def log_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances between multipliers as Floquet exponents (log mu, its angle wrapped to (-pi, pi]): a multiplier
    exp(sigma T) moves by the change of sigma T whatever its size, so a large one that triples is as far as a
    small one that triples."""
    la, lb = np.log(np.maximum(np.abs(a), 1e-300)), np.log(np.maximum(np.abs(b), 1e-300))
    turn = np.angle(np.exp(1j * (np.angle(a)[:, None] - np.angle(b)[None, :])))
    return np.hypot(la[:, None] - lb[None, :], turn)


def _assignment(cost: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """The least total cost of pairing the rows of ``cost`` with its columns (as many pairs as the shorter side;
    inf entries are forbidden pairs: inf when no assignment avoids them), with the pairs (rows, cols)."""
    if cost.size == 0:
        return 0.0, np.zeros(0, int), np.zeros(0, int)
    finite = np.isfinite(cost)
    big = 1.0 + cost.shape[0] * cost.shape[1] * (np.max(cost[finite]) if finite.any() else 1.0)
    rows, cols = linear_sum_assignment(np.where(finite, cost, big))
    total = cost[rows, cols]
    return (float(np.sum(total)) if np.all(np.isfinite(total)) else np.inf), rows, cols


def untracked_multipliers(before: np.ndarray, after: np.ndarray) -> bool:
    """:func:`untracked` for multipliers (unstable: outside the unit circle)."""
    return untracked(before, after, _outside, _from_circle, log_distance)


def name_crossings(spectrum: np.ndarray, count: int, distance, pair: str, real,
                   crossed: list[int] = ()) -> list[tuple[str, complex]]:
    """(event name, member) for ``count`` crossings: the members of ``spectrum`` known to have crossed first
    (``crossed``, indices from :func:`crossed_members`), then those nearest the stability boundary
    (``distance(z)`` from it), which a member that did not cross can be; ``pair`` for a complex pair (counted
    twice; its upper member), ``real(z)`` for a real value."""
    z = np.asarray(spectrum, complex)
    names, left = [], int(count)
    cz = z[list(crossed)]

    def did_cross(k):  # closed under conjugation: matching may list either member of a pair
        tol = 1e-12 * max(1.0, abs(z[k]))
        return cz.size > 0 and min(np.min(np.abs(cz - z[k])), np.min(np.abs(cz - np.conj(z[k])))) <= tol

    order = sorted(range(len(z)), key=lambda k: (not did_cross(k), distance(z[k])))
    for k in order:
        if left <= 0:
            break
        v = z[k]
        if abs(v.imag) > IMAG_TOL * max(1.0, abs(v)):
            if v.imag > 0:  # each pair once, by its upper member
                names.append((pair, complex(v)))
                left -= 2
        else:
            names.append((real(v), complex(v)))
            left -= 1
    return names


def classify(kind: str, mu: np.ndarray, n_trivial: int) -> dict[str, Any] | None:
    """Type-specific data of an event at multipliers ``mu``, or None when the sign change is not a bifurcation:
    for NS, the pair whose product is closest to 1 must be complex (else a neutral saddle); its angle is
    returned."""
    if kind != "NS":
        return {}
    nt = _conjugate_closed(nontrivial(mu, n_trivial))
    if len(nt) < 2:
        return None
    i, j = np.triu_indices(len(nt), 1)
    k = int(np.argmin(np.abs(nt[i] * nt[j] - 1.0)))
    a, b = nt[i[k]], nt[j[k]]
    complex_pair = abs(a.imag) > IMAG_TOL * max(1.0, abs(a)) and abs(a - np.conj(b)) <= 1e-6 * max(1.0, abs(a))
    return {"angle": float(abs(np.angle(a)))} if complex_pair else None


def ns_angle(mu: np.ndarray, n_trivial: int) -> float:
    """arg of the complex multiplier of the pair whose product is closest to 1, in (0, pi); NaN if none."""
    c = classify("NS", mu, n_trivial)
    return float("nan") if c is None else c["angle"]


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
    n = G.shape[1]
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
