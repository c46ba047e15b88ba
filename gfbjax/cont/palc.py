r"""Pseudo-arclength continuation of periodic orbits in lam.

One step from a converged point :math:`X_k=(x_k, T_k, \lambda_k)` with unit
tangent :math:`\tau_k` (paper Eq. (34): the augmented Jacobian times
:math:`\tau` equals the last unit vector, the last row being the previous
tangent, so orientation is preserved automatically):

1. predictor :math:`X^{(0)} = X_k + \Delta s\,\tau_k` (tangent) or along the
   secant :math:`X_k - X_{k-1}`;
2. corrector: Newton on (27)-(29) plus the pseudo-arclength row (30)
   :math:`\langle X - X_k, \tau_k\rangle = \Delta s`, phase reference = predictor;
3. adaptive step: ``ds *= grow`` after convergence within ``fast_iter``
   iterations, ``ds /= 2`` after a failure; the branch ends (with a reason)
   when ``|ds| < ds_min``, lam leaves [lam_min, lam_max] or ``max_points``
   points were computed.

``mode="natural"`` replaces (30) by :math:`\lambda = \lambda_k + \Delta s`
(predictor: previous orbit, or secant extrapolation) -- a fallback that fails
at folds.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Any, Callable, Optional

import jax
import jax.numpy as jnp
import numpy as np

from . import collocation as col
from .branch import Branch, PointRecord
from .events import cycle_test_functions, detect, double_orbit_pd, locate, ns_angle
from .floquet import multipliers_periodic, multipliers_product, nontrivial, trivial_error
from .problem import check_step_settings, CycleProblem, check_range


@dataclass(frozen=True)
class CycleSettings:
    """Settings of cycle continuation (validated at construction).

    m, N: collocation points per interval and mesh intervals (for starts built
    from samples / Hopf points; a given start orbit keeps its own mesh).
    ds: initial step (> 0); direction: +1/-1 initial orientation in lam.
    dlam_max: largest *predicted* change of lam in one step (caps ds when the tangent is nearly
    orthogonal to lam in the arclength metric; the corrector may move lam further; inf = no cap).
    linear_solver: "dense" (condensation of parameters, all n multipliers), "sparse" (per-interval sparse LU,
    GMRES and Arnoldi, the ``n_multipliers`` largest multipliers; needs ``problem.jac_sparsity``) or "auto"
    (sparse when the problem has a pattern and n >= SPARSE_MIN_N).
    """

    m: int = 4
    N: int = 20
    ds: float = 0.05
    ds_min: float = 1e-6
    ds_max: float = 0.5
    direction: int = 1
    max_points: int = 100
    lam_min: float = -np.inf
    lam_max: float = np.inf
    dlam_max: float = np.inf
    newton_tol: float = 1e-9
    newton_step_tol: float = 1e-9
    newton_max_iter: int = 8
    fast_iter: int = 3
    grow: float = 1.5
    mode: str = "palc"
    predictor: str = "tangent"
    detect: tuple[str, ...] = ("LPC", "PD", "NS")
    locate: bool = True
    locate_tol: float = 1e-8
    floquet: str = "periodic"
    save_states: bool = False
    linear_solver: str = "auto"
    n_multipliers: int = 12

    def __post_init__(self) -> None:
        check_range("m", self.m, 2, 7, integer=True)
        check_range("N", self.N, 2, 10**6, integer=True)
        check_step_settings(self)
        if not (isinstance(self.dlam_max, (int, float)) and self.dlam_max > 0.0):
            raise ValueError(f"dlam_max must be in (0, inf], got {self.dlam_max!r}")
        if not self.lam_min < self.lam_max:
            raise ValueError(f"lam_min must be < lam_max, got lam_min={self.lam_min}, lam_max={self.lam_max}")
        check_range("newton_tol", self.newton_tol, 0.0, 1.0, lo_open=True)
        check_range("newton_step_tol", self.newton_step_tol, 0.0, 1.0, lo_open=True)
        check_range("newton_max_iter", self.newton_max_iter, 1, 1000, integer=True)
        check_range("fast_iter", self.fast_iter, 1, self.newton_max_iter, integer=True)
        check_range("grow", self.grow, 1.0, 10.0)
        if self.mode not in ("palc", "natural"):
            raise ValueError(f"mode must be 'palc' or 'natural', got {self.mode!r}")
        if self.predictor not in ("tangent", "secant"):
            raise ValueError(f"predictor must be 'tangent' or 'secant', got {self.predictor!r}")
        bad = [d for d in self.detect if d not in ("LPC", "PD", "NS")]
        if bad:
            raise ValueError(f"detect entries must be in ('LPC', 'PD', 'NS'), got {bad}")
        check_range("locate_tol", self.locate_tol, 0.0, 1.0, lo_open=True)
        if self.floquet not in ("periodic", "product"):
            raise ValueError(f"floquet must be 'periodic' or 'product', got {self.floquet!r}")
        if self.linear_solver not in ("auto", "dense", "sparse"):
            raise ValueError(f"linear_solver must be 'auto', 'dense' or 'sparse', got {self.linear_solver!r}")
        check_range("n_multipliers", self.n_multipliers, 1, 10**6, integer=True)


@dataclass(frozen=True)
class CycleStart:
    """Where a branch starts.  ``tangent=None``: ``orbit`` is a guess corrected
    at fixed lam, the first tangent points to increasing lam * direction.
    Otherwise ``orbit`` is a bifurcation point (Hopf / PD) and ``tangent`` the
    direction of the emanating branch (the start itself is not recorded)."""

    orbit: col.Orbit
    tangent: Optional[col.Orbit] = None
    label: str = "start"


# ---------------------------------------------------------------- starts
def start_from_samples(t: np.ndarray, x: np.ndarray, T: float, lam: float,
                       settings: CycleSettings, mesh: Any = None) -> CycleStart:
    """From a time-integrated orbit: samples ``x[i] = x(t[i])`` over one period T."""
    sch = col.Scheme(settings.m)
    mesh = col.uniform_mesh(settings.N) if mesh is None else mesh
    return CycleStart(col.orbit_from_samples(t, x, T, lam, sch, mesh), None, "samples")


def start_from_function(x_of_t: Callable[[np.ndarray], np.ndarray], T: float, lam: float,
                        settings: CycleSettings, mesh: Any = None) -> CycleStart:
    """From a function of the scaled time t in [0,1] (vectorised, returns (len(t), n))."""
    sch = col.Scheme(settings.m)
    mesh = col.uniform_mesh(settings.N) if mesh is None else mesh
    return CycleStart(col.orbit_from_function(x_of_t, T, lam, sch, mesh), None, "function")


def start_from_hopf(hopf: Any, settings: CycleSettings) -> CycleStart:
    """From a Hopf point (``lam, x, omega, v``): x(t) = x0 + a Re(v e^{2 pi i t}).

    The start is the stationary orbit x0 with T = 2 pi / omega; the tangent is
    the normalised first harmonic Re(v e^{2 pi i t}) (lam, T components 0, the
    Hopf bifurcation being a pitchfork in the amplitude a)."""
    sch = col.Scheme(settings.m)
    mesh = col.uniform_mesh(settings.N)
    x0 = np.asarray(hopf.x, float)
    v = np.asarray(hopf.v, complex)
    T = 2 * np.pi / float(hopf.omega)
    base = col.orbit_from_function(lambda t: np.tile(x0, (len(t), 1)), T, hopf.lam, sch, mesh)
    phi = col.orbit_from_function(lambda t: np.real(v[None, :] * np.exp(2j * np.pi * t)[:, None]),
                                  0.0, 0.0, sch, mesh)
    phi = phi.scale(1.0 / float(jnp.sqrt(col.inner(phi, phi, sch))))
    return CycleStart(base, phi, "hopf")


def start_from_branch(branch: Branch, index: int) -> CycleStart:
    """From a stored point of a branch computed with ``save_states=True``."""
    if branch.states is None:
        raise ValueError("branch has no stored states (use CycleSettings(save_states=True))")
    s = branch.states
    o = col.Orbit(jnp.asarray(s["mesh"]), jnp.asarray(s["xm"][index]), jnp.asarray(s["xi"][index]),
                  jnp.asarray(s["T"][index]), jnp.asarray(s["lam"][index]))
    return CycleStart(o, None, f"branch[{index}]")


def start_from_pd(problem: CycleProblem, branch: Branch, special: int | dict,
                  settings: "CycleSettings | None" = None) -> CycleStart:
    """Switch onto the period-doubled branch at a located PD point of ``branch`` (transfer matrices from the
    backend that ``settings`` selects)."""
    sp_list = branch.special_of("PD") if isinstance(special, int) else [special]
    sp = sp_list[special] if isinstance(special, int) else special
    st = branch.special_states[sp["state"]]
    sch = col.Scheme(int(branch.m))
    o = col.Orbit(jnp.asarray(st["mesh"]), jnp.asarray(st["xm"]), jnp.asarray(st["xi"]),
                  jnp.asarray(st["T"]), jnp.asarray(st["lam"]))
    G = make_backend(problem, sch, settings).transfer_matrices(o)
    doubled, direction = double_orbit_pd(problem.f, problem.args, o, sch, np.asarray(G))
    return CycleStart(doubled, direction, "PD switch")


# ---------------------------------------------------------------- helpers
_transfer = jax.jit(col.transfer_matrices, static_argnums=(0, 3))

SPARSE_MIN_N = 80  # dense condensation (all n multipliers) below; sparse is ~8x faster per Newton solve at n = 102


class DenseBackend:
    """Linear algebra by dense condensation of parameters (``collocation.py``); all n multipliers."""

    def __init__(self, problem: CycleProblem, scheme: col.Scheme, floquet: str = "periodic"):
        self.problem, self.scheme, self.floquet = problem, scheme, floquet

    def newton(self, orbit, con, **kw) -> col.NewtonResult:
        return col.newton(self.problem.f, self.problem.args, orbit, con, self.scheme, **kw)

    def multipliers(self, orbit: col.Orbit) -> np.ndarray:
        G = np.asarray(_transfer(self.problem.f, self.problem.args, orbit, self.scheme))
        if self.floquet == "periodic":
            return multipliers_periodic(G).multipliers
        mu = multipliers_product(G)
        return mu[np.argsort(-np.abs(mu))]

    def transfer_matrices(self, orbit: col.Orbit) -> np.ndarray:
        return np.asarray(_transfer(self.problem.f, self.problem.args, orbit, self.scheme))


def make_backend(problem: CycleProblem, scheme: col.Scheme, settings: "CycleSettings | None" = None):
    """The linear-algebra backend for ``problem`` (see ``CycleSettings.linear_solver``)."""
    s = settings or CycleSettings()
    choice = s.linear_solver
    if choice == "auto":
        choice = "sparse" if problem.jac_sparsity is not None and problem.n >= SPARSE_MIN_N else "dense"
    if choice == "sparse":
        if problem.jac_sparsity is None:
            raise ValueError("linear_solver='sparse' needs CycleProblem.jac_sparsity (the pattern of df/dx)")
        from .sparse_colloc import SparseCollocation

        return SparseCollocation(problem.f, problem.args, problem.n, problem.jac_sparsity, scheme,
                                 n_multipliers=s.n_multipliers)
    return DenseBackend(problem, scheme, s.floquet)


@partial(jax.jit, static_argnums=(1,))
def _norm_and_extrema(orbit: col.Orbit, scheme: col.Scheme, comps: jax.Array):
    U = orbit.nodes()[..., comps]
    return col.l2_norm(orbit, scheme), jnp.max(U, axis=(0, 1)), jnp.min(U, axis=(0, 1))


def analyse(problem: CycleProblem, orbit: col.Orbit, scheme: col.Scheme, method: str = "periodic",
            backend: Any = None):
    """Floquet multipliers (decreasing modulus), stability, trivial-multiplier error.

    ``backend`` (from :func:`make_backend`) selects the linear algebra; default: dense with ``method``."""
    backend = backend if backend is not None else DenseBackend(problem, scheme, method)
    mu = backend.multipliers(orbit)
    nt = nontrivial(mu, problem.n_trivial)
    stable = bool(np.all(np.abs(nt) < 1.0))
    return mu, stable, trivial_error(mu)


def _record(problem, orbit, scheme, settings, mu, stable, terr, iters, ds, tlam) -> PointRecord:
    l2, xmax, xmin = _norm_and_extrema(orbit, scheme, jnp.asarray(problem.components))
    state = None
    if settings.save_states:
        state = {"xm": np.asarray(orbit.xm), "xi": np.asarray(orbit.xi), "T": np.asarray(orbit.T),
                 "lam": np.asarray(orbit.lam)}
    return PointRecord(float(orbit.lam), float(orbit.T), float(l2), np.asarray(xmax), np.asarray(xmin),
                       mu, stable, terr, int(iters), float(ds), float(tlam), state)


def _orbit_state(orbit: col.Orbit) -> dict[str, np.ndarray]:
    return {"mesh": np.asarray(orbit.mesh), "xm": np.asarray(orbit.xm), "xi": np.asarray(orbit.xi),
            "T": np.asarray(orbit.T), "lam": np.asarray(orbit.lam)}


def _correct(backend, settings, pred: col.Orbit, con: col.Constraint) -> col.NewtonResult:
    return backend.newton(pred, con, tol=settings.newton_tol, rtol_step=settings.newton_step_tol,
                          max_iter=settings.newton_max_iter)


# ---------------------------------------------------------------- main loop
def continue_cycles(problem: CycleProblem, settings: CycleSettings, start: CycleStart, *,
                    callback: Optional[Callable[[int, PointRecord], Any]] = None,
                    progress: bool = False) -> Branch:
    """Continue a branch of periodic orbits; see module docstring.

    ``callback(index, record)`` is called after each accepted point (return
    ``False`` to stop).  Returns a ``Branch``; it is returned (with the points
    computed so far and the reason) whatever ends the continuation.
    """
    scheme = col.Scheme(int(start.orbit.xi.shape[1]) + 1)
    points: list[PointRecord] = []
    special: list[dict[str, Any]] = []
    special_states: list[dict[str, np.ndarray]] = []
    reason = "unknown"
    backend = make_backend(problem, scheme, settings)  # a bad choice raises here, before any work
    bar = None
    if progress:
        try:
            from tqdm.auto import tqdm
            bar = tqdm(total=settings.max_points, desc="cycles")
        except ImportError:  # pragma: no cover
            bar = None
    shared = {"mesh": np.asarray(start.orbit.mesh)} if settings.save_states else None
    try:
        reason = _loop(problem, settings, scheme, backend, start, points, special, special_states, callback, bar)
    except KeyboardInterrupt:
        reason = "interrupted"
    except Exception as e:  # never lose the computed branch
        reason = f"error: {e!r}"
    finally:
        if bar is not None:
            bar.close()
    return Branch.from_points("cycles", problem.components, points, special, special_states, reason,
                              m=scheme.m, shared_state=shared)


def _loop(problem, settings, scheme, backend, start, points, special, special_states, callback, bar) -> str:
    s = settings
    palc = s.mode == "palc"
    if start.tangent is None:
        con = col.natural_constraint(start.orbit, start.orbit.lam)
        res = _correct(backend, s, start.orbit, con)
        if not res.converged:
            return f"start point did not converge: {res.reason}"
        X = res.orbit
        tau = res.tangent.scale(float(s.direction))
        mu, stable, terr = analyse(problem, X, scheme, backend=backend)
        points.append(_record(problem, X, scheme, s, mu, stable, terr, res.iterations, 0.0, tau.lam))
        tests = cycle_test_functions(mu, problem.n_trivial, float(tau.lam))
        if callback is not None and callback(0, points[-1]) is False:
            return "stopped by callback"
    else:
        X, tau, mu, tests = start.orbit, start.tangent, None, None
    X_prev: Optional[col.Orbit] = None
    ds = s.ds
    while len(points) < s.max_points:
        # ---- predictor
        if palc:
            direction = tau
            if s.predictor == "secant" and X_prev is not None:
                sec = X + X_prev.scale(-1.0)
                direction = sec.scale(1.0 / float(jnp.sqrt(col.inner(sec, sec, scheme))))
            # cap the parameter change per step: the arclength metric can be dominated by T or by many states
            ds = min(ds, s.dlam_max / max(abs(float(direction.lam)), 1e-300))
            pred = X + direction.scale(ds)
            con = col.palc_constraint(X, direction, ds, ref=pred)
        else:
            ds = min(ds, s.dlam_max)
            step = ds * float(s.direction)
            pred = X
            if X_prev is not None:
                pred = X + (X + X_prev.scale(-1.0)).scale(step / float(X.lam - X_prev.lam))
            con = col.natural_constraint(pred, X.lam + step)
        res = _correct(backend, s, pred, con)
        if not res.converged:
            ds *= 0.5
            if ds < s.ds_min:
                return f"step size below ds_min={s.ds_min} ({res.reason})"
            continue
        Xn = res.orbit
        tau_n = res.tangent
        if not palc:
            tau_n = tau_n.scale(float(s.direction))
        mu_n, stable_n, terr_n = analyse(problem, Xn, scheme, backend=backend)
        tests_n = cycle_test_functions(mu_n, problem.n_trivial, float(tau_n.lam))
        # ---- events between X and Xn
        if tests is not None and s.detect:
            for kind in detect(tests, tests_n, s.detect):
                _handle_event(problem, s, scheme, backend, kind, X, tau if palc else None, ds, tests, tests_n,
                              Xn, mu_n, points, special, special_states)
        rec = _record(problem, Xn, scheme, s, mu_n, stable_n, terr_n, res.iterations, ds, tau_n.lam)
        points.append(rec)
        if bar is not None:
            bar.update(1)
        if callback is not None and callback(len(points) - 1, rec) is False:
            return "stopped by callback"
        X_prev, X, tau, tests = X, Xn, tau_n, tests_n
        lam = float(Xn.lam)
        if not (s.lam_min <= lam <= s.lam_max):
            return f"lam={lam:.6g} left [lam_min, lam_max]"
        if res.iterations <= s.fast_iter:
            ds = min(ds * s.grow, s.ds_max)
    return "max_points reached"


def _handle_event(problem, s, scheme, backend, kind, X, tau, ds, tests, tests_n, Xn, mu_n, points, special,
                  special_states) -> None:
    """Localise ``kind`` between X (left) and Xn and insert the special point."""
    orbit, mu, located = Xn, mu_n, False
    tl = float("nan")
    if s.locate and tau is not None:
        def g(sv):
            con = col.palc_constraint(X, tau, sv, ref=X + tau.scale(sv))
            r = _correct(backend, s, X + tau.scale(sv), con)
            if not r.converged:
                return float("nan"), None
            t = r.tangent
            m_, _, _ = analyse(problem, r.orbit, scheme, backend=backend)
            val = cycle_test_functions(m_, problem.n_trivial, float(t.lam))[kind]
            return val, (r, m_, float(t.lam))

        sv, payload, val, located = locate(g, ds, tests[kind], tests_n[kind], tol=s.locate_tol)
        if payload is not None:
            r, mu, tl = payload
            orbit = r.orbit
            stable = bool(np.all(np.abs(nontrivial(mu, problem.n_trivial)) < 1.0))
            points.append(_record(problem, orbit, scheme, s, mu, stable, trivial_error(mu),
                                  r.iterations, sv, tl))
        else:
            located = False
    index = len(points) - 1 if located else len(points)
    special_states.append(_orbit_state(orbit))
    special.append({"type": kind, "index": index, "lam": float(orbit.lam), "period": float(orbit.T),
                    "multipliers": np.asarray(mu), "located": bool(located),
                    "angle": ns_angle(mu, problem.n_trivial) if kind == "NS" else None,
                    "state": len(special_states) - 1})
