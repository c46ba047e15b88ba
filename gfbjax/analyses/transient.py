"""Time integration of the GFB-rotor system with diffrax: constant speed (Eq. 15a) and run-up / coast-down at
constant angular acceleration (Eq. 15b), paper Sect. 3.2.

Both cases integrate :func:`gfbjax.model.runup_vector_field` ``f(tau, s, params, omega0, accel)``: with
``accel = 0`` it *is* Eq. (17) with Eq. (15a) (speed ``omega0``, unbalance phase ``omega0 tau``), so one compiled
solver serves constant-speed runs and run-ups alike (a test checks the identity against
:func:`gfbjax.model.forced_vector_field`).  All quantities are dimensionless (docs/model.md): time ``tau = t / t*``,
speed ``Omega_bar = Omega t*``, displacements over the clearance ``c``, acceleration ``a_bar = a t*^2``.

Solver (chosen by measurement): diffrax ``Kvaerno5`` (L-stable ESDIRK, order 5(4)) with a PID step-size
controller (pcoeff 0.3, icoeff 0.4; a plain I controller rejected half of the steps).  Its Newton iteration is a
chord method with one Jacobian and one dense LU factorisation (lineax ``LU``) per *step*, reused by all stages
(diffrax' ``VeryChord`` logic).  The Jacobian is assembled by :class:`ColoredChord` from a column colouring of the
sparsity pattern (23 JVPs + 2 VJPs for 431 states instead of 431 JVPs; :func:`jacobian_coloring`), which halves the
cost per step; ``TransientSettings(jacobian="dense")`` uses diffrax' own ``VeryChord``.  The LU stays dense: the
journal-acceleration rows couple every pressure, and a ~300 x 300 LU costs about as much as one Jacobian.

Measured (``benchmarks/transient_speed.py``, default grid Nx=48, Nz=8: 431 states, Omega_bar = 0.5, 3 revolutions
from the equilibrium, 2-core CPU, one BLAS thread): Kvaerno5 with the coloured Jacobian gives 1.02 revolutions per
second at rtol 1e-5 (end-state error 1.1e-6 against an rtol-1e-9 reference) and 0.64 rev/s at rtol 1e-6 (1.3e-7);
diffrax' dense VeryChord Jacobian 0.33 rev/s; scipy ``solve_ivp`` Radau with the exact jitted Jacobian 0.64 rev/s
(2.7e-7), BDF 2.28 rev/s (5.2e-6; it reuses Jacobians over many steps).  Multi-threaded BLAS on a small shared
machine made these small LUs 50-100x slower, hence ``OPENBLAS_NUM_THREADS=1`` by default (``gfbjax._process``).

Long runs are integrated in chunks of ``chunk_revs`` revolutions: one compiled ``diffeqsolve`` per
(grid, settings), reused by every chunk, a progress bar advanced per chunk, and everything computed up to a
failing chunk is kept.  Rub: a diffrax :class:`~diffrax.Event` stops the run when the minimum film thickness falls
to ``h_rub``; the result then has ``outcome == Outcome.RUB`` and all data up to the contact (never NaN).

Public API: :class:`TransientSettings`, :class:`TransientResult`, :func:`simulate` (constant speed),
:func:`run_up` (run-up or coast-down), :func:`runup_acceleration`, :func:`default_initial_state`.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import zipfile
import math
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import lineax as lx
import optimistix as optx
from jax import Array

from ..cont import Coloring, Outcome, color_pattern, dense_jacobian
from ..model import film, layout, runup_vector_field
from .. import limits
from ..params import ParameterError, Params, check_params

__all__ = [
    "SOLVERS",
    "TransientSettings",
    "TransientResult",
    "simulate",
    "run_up",
    "runup_acceleration",
    "RunPlan",
    "check_simulate",
    "check_run_up",
    "default_initial_state",
    "outputs_of",
]

SOLVERS: dict[str, Callable[[], dfx.AbstractSolver]] = {
    "kvaerno3": dfx.Kvaerno3,
    "kvaerno4": dfx.Kvaerno4,
    "kvaerno5": dfx.Kvaerno5,
}

OUTCOMES = (Outcome.COMPLETED, Outcome.RUB, Outcome.INTEGRATION_FAILED)


# Ranges of the TransientSettings fields (only this class uses them; the shared ranges are in gfbjax.limits).
_SETTINGS_RANGES = (
    limits.Range("rtol", 1e-13, 1e-1), limits.Range("atol", 1e-15, 1e-1), limits.Range("chunk_revs", 1e-3, 1e5),
    limits.Range("h_rub", 0.0, 0.5), limits.Range("pcoeff", 0.0, 1.0), limits.Range("icoeff", 0.0, 1.0),
    limits.Range("samples_per_rev", 4, 4096, integer=True),
    limits.Range("max_steps_per_chunk", 10, 10**8, integer=True),
)


@dataclass(frozen=True)
class TransientSettings:
    """Settings of a transient run (checked when built; the message names the field and its range).

    Attributes:
        solver: ``"kvaerno5"`` (default), ``"kvaerno4"`` or ``"kvaerno3"`` (diffrax ESDIRK methods).
        rtol, atol: relative and absolute local error tolerances of the PID step-size controller (states are
            dimensionless: pressures ~1, displacements ~0.1-1, velocities ~0.01-0.1).
        samples_per_rev: saved samples per revolution (at the highest speed of a run-up; exactly per revolution at
            constant speed, where sample ``k * samples_per_rev`` lies at unbalance phase ``2 pi k``).
        chunk_revs: revolutions (at the highest speed) per chunk; one compiled solve serves every chunk.
        h_rub: film thickness ``h_min / c`` at which the run stops with outcome ``"rub"``.
        max_steps_per_chunk: diffrax ``max_steps`` of one chunk.
        save_states: also keep the full state vector at every sample (memory: n_states x samples).
        pcoeff, icoeff: PID controller coefficients (diffrax' recommendation for stiff ESDIRK: 0.3, 0.4).
        jacobian: ``"colored"`` (default: sparse Jacobian by column colouring, :class:`ColoredChord`) or
            ``"dense"`` (diffrax' own VeryChord: one JVP per state).
    """

    solver: str = "kvaerno5"
    rtol: float = 1e-6
    atol: float = 1e-8
    samples_per_rev: int = 32
    chunk_revs: float = 10.0
    h_rub: float = 0.01
    max_steps_per_chunk: int = 200_000
    save_states: bool = False
    pcoeff: float = 0.3
    icoeff: float = 0.4
    jacobian: str = "colored"

    def __post_init__(self) -> None:
        if self.solver not in SOLVERS:
            raise ParameterError(f"solver = {self.solver!r} is not one of {sorted(SOLVERS)}")
        if self.jacobian not in ("colored", "dense"):
            raise ParameterError(f"jacobian = {self.jacobian!r} is not one of ['colored', 'dense']")
        for rng in _SETTINGS_RANGES:  # NumPy numbers are stored as Python numbers
            object.__setattr__(self, rng.name, rng.check(getattr(self, rng.name)))

    def replace(self, **changes: Any) -> "TransientSettings":
        return dataclasses.replace(self, **changes)


# -- results -------------------------------------------------------------------------------------------------------


@dataclass
class TransientResult:
    """Samples of a transient run (dimensionless; see the module docstring).

    Attributes:
        tau: sample times, shape (M,).  ``tau = 0`` is the start of the run; the unbalance phase is
            ``omega0 tau + accel tau^2 / 2``.
        speed: running speed Omega_bar at each sample, (M,).
        rotor: rotor states at each sample, (M, n_rotor): Jeffcott ``[x_j, y_j, x_d, y_d, x_j', y_j', x_d', y_d']``,
            rigid ``[x_j, y_j, x_j', y_j']`` (over c, primes d/dtau; y up).
        h_min: minimum film thickness over c at each sample, (M,).
        final_state: full state at the last sample (a run can be continued from it).
        outcome: :class:`gfbjax.cont.Outcome`: ``COMPLETED``, ``RUB`` (film reached ``h_rub``; the last sample is
            the contact), ``INTEGRATION_FAILED`` (solver failure; the samples up to the failing chunk are kept) or
            ``INTERRUPTED`` (the samples up to the last finished chunk are kept).
        message: one sentence on the outcome.
        omega0, accel: start speed and angular acceleration (0 at constant speed).
        samples_per_rev: samples per revolution (at the top speed of a run-up).
        rotor_kind: ``"jeffcott"`` or ``"rigid"``.
        stats: ``steps``, ``accepted``, ``rejected``, ``wall_s`` (integration, compile included), ``compile_s``
            (first chunk minus the mean of the others, an estimate), ``steps_per_s``, ``revs_per_s``, ``chunks``.
        settings: the :class:`TransientSettings` as a dict.
        states: full states at every sample (M, n) when ``save_states`` was set, else None.
    """

    tau: np.ndarray
    speed: np.ndarray
    rotor: np.ndarray
    h_min: np.ndarray
    final_state: np.ndarray
    outcome: str
    message: str
    omega0: float
    accel: float
    samples_per_rev: int
    rotor_kind: str
    stats: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    states: np.ndarray | None = None

    # -- named views -------------------------------------------------------------------------------------------
    @property
    def x_j(self) -> np.ndarray:
        """Journal horizontal displacement over c."""
        return self.rotor[:, 0]

    @property
    def y_j(self) -> np.ndarray:
        """Journal vertical displacement over c (y up)."""
        return self.rotor[:, 1]

    @property
    def x_d(self) -> np.ndarray | None:
        """Disc horizontal displacement over c (None for the rigid rotor)."""
        return self.rotor[:, 2] if self.rotor_kind == "jeffcott" else None

    @property
    def y_d(self) -> np.ndarray | None:
        """Disc vertical displacement over c (None for the rigid rotor)."""
        return self.rotor[:, 3] if self.rotor_kind == "jeffcott" else None

    @property
    def phase(self) -> np.ndarray:
        """Unbalance phase ``phi = omega0 tau + accel tau^2 / 2`` [rad] at each sample."""
        return self.omega0 * self.tau + 0.5 * self.accel * self.tau**2

    @property
    def revolutions(self) -> float:
        """Revolutions simulated (unbalance phase / 2 pi at the last sample)."""
        return float(abs(self.phase[-1]) / (2 * math.pi)) if self.tau.size else 0.0

    @property
    def constant_speed(self) -> bool:
        return self.accel == 0.0

    @property
    def completed(self) -> bool:
        return self.outcome == Outcome.COMPLETED

    def poincare(self, last: int | None = None) -> np.ndarray:
        """Once-per-revolution samples (unbalance phase = 0 mod 2 pi) of a constant-speed run: indices
        ``0, N, 2N, ...`` with N = samples_per_rev.  Returns the rotor states there, (K, n_rotor); ``last``
        keeps only the last K revolutions (the paper plots the last 100 of 500)."""
        if not self.constant_speed:
            raise ValueError("poincare() needs a constant-speed run (accel == 0)")
        idx = np.arange(0, self.tau.size, self.samples_per_rev)
        pts = self.rotor[idx]
        return pts if last is None else pts[-last:]

    def window(self, revs: float) -> slice:
        """Slice of the samples of the last ``revs`` revolutions (an integer number of samples per revolution)."""
        n = int(round(revs * self.samples_per_rev))
        return slice(max(0, self.tau.size - n - 1), self.tau.size)

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary of the run."""
        return {
            "outcome": self.outcome, "message": self.message, "omega0": self.omega0, "accel": self.accel,
            "speed_end": float(self.speed[-1]) if self.speed.size else self.omega0,
            "tau_end": float(self.tau[-1]) if self.tau.size else 0.0, "revolutions": self.revolutions,
            "samples": int(self.tau.size), "h_min": float(self.h_min.min()) if self.h_min.size else None,
            "stats": self.stats, "settings": self.settings,
        }

    # -- persistence -------------------------------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        """Write the result to an ``.npz`` file (arrays plus a JSON header)."""
        path = Path(path)
        meta = {"outcome": self.outcome, "message": self.message, "omega0": self.omega0, "accel": self.accel,
                "samples_per_rev": self.samples_per_rev, "rotor_kind": self.rotor_kind,
                "stats": self.stats, "settings": self.settings}
        arrays = dict(tau=self.tau, speed=self.speed, rotor=self.rotor, h_min=self.h_min,
                      final_state=self.final_state, meta=np.array(json.dumps(meta, default=_json_default)))
        if self.states is not None:
            arrays["states"] = self.states
        np.savez_compressed(path, **arrays)
        return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> "TransientResult":
        """Read a result written by :meth:`save`; ValueError (one line, naming the file) for a missing, corrupt or
        foreign file."""
        try:
            with np.load(Path(path), allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                meta["outcome"] = Outcome(_LEGACY_OUTCOMES.get(meta["outcome"], meta["outcome"]))
                states = z["states"] if "states" in z.files else None
                return cls(tau=z["tau"], speed=z["speed"], rotor=z["rotor"], h_min=z["h_min"],
                           final_state=z["final_state"], states=states, **meta)
        except (OSError, EOFError, KeyError, TypeError, ValueError, zipfile.BadZipFile) as exc:
            first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ValueError(f"{path}: not a readable gfbjax transient result ({first})") from None


_LEGACY_OUTCOMES = {"failed": "integration_failed"}  # the name before the shared Outcome vocabulary


def _json_default(o: Any) -> Any:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o)}")


# -- helpers ---------------------------------------------------------------------------------------------------------


def outputs_of(s: Array, params: Params) -> tuple[Array, Array]:
    """(rotor states, minimum film thickness) of a state vector; works on a batch of states too."""
    lay = layout(params)
    if s.ndim == 2:
        return lay.rotor(s), jax.vmap(lambda y: jnp.min(film(y, params)))(s)
    return lay.rotor(s), jnp.min(film(s, params))


def default_initial_state(params: Params, omega: float) -> tuple[np.ndarray, str]:
    """The static equilibrium of the balanced system at ``omega`` (:func:`gfbjax.analyses.static.solve_equilibrium`), as
    the start of a run, and a note on it."""
    from .static import solve_equilibrium

    res = solve_equilibrium(params.traced(), float(omega))
    note = f"started from the static equilibrium at Omega_bar = {omega:g} ({res.outcome})"
    return np.asarray(res.state), note


def runup_acceleration(omega_start: float, omega_end: float, revolutions: float) -> float:
    """Constant angular acceleration ``a_bar`` [per tau^2] that takes ``revolutions`` revolutions to go from
    ``omega_start`` to ``omega_end``: ``(omega_end^2 - omega_start^2) / (4 pi revolutions)``."""
    revolutions = limits.REVOLUTIONS.check(revolutions)
    return (omega_end**2 - omega_start**2) / (4.0 * math.pi * revolutions)


# -- sparse (coloured) Jacobian for the implicit stages -------------------------------------------------------------


@functools.lru_cache(maxsize=16)
def _coloring_cached(Nx: int, Nz: int, rotor: str, gumbel_width: float, axial_domain: str = "half") -> Coloring:
    from ..model.pattern import jacobian_sparsity
    from ..params import reference_system

    params = reference_system(Nx=Nx, Nz=Nz, rotor=rotor, gumbel_width=gumbel_width,
                              axial_domain=axial_domain).nondim()
    return color_pattern(jacobian_sparsity(params, oscillator=False))


def jacobian_coloring(params: Params) -> Coloring:
    """The column colouring (:class:`gfbjax.cont.Coloring`) of this system's Jacobian, cached per grid and rotor.

    The Jacobian of the stage equations of an implicit Runge-Kutta method, ``I - gamma dt J``, has the sparsity of
    ``J`` plus the diagonal.  ``J`` is sparse except for the rows of the journal accelerations (the bearing force
    integrates every pressure): those dense rows are taken by reverse mode (one VJP each), the rest by one
    forward-mode JVP per colour.  Reference grid Nx=40, Nz=6 (281 states): 25 JVPs + 2 VJPs instead of 281 JVPs."""
    return _coloring_cached(params.Nx, params.Nz, params.rotor, float(params.gumbel_width), params.axial_domain)


class ColoredChord(optx.AbstractRootFinder):
    """diffrax' ``VeryChord`` (one linearisation per Runge-Kutta step, reused by every stage) with the Jacobian
    of the stage equations assembled from a :class:`gfbjax.cont.Coloring` and factorised by lineax' dense ``LU``.
    The chord iterations, convergence test and divergence test are VeryChord's own."""

    rtol: float
    atol: float
    coloring: Coloring = eqx.field(static=True)
    norm: Callable = optx.max_norm
    kappa: float = 1e-2

    def _chord(self):
        from diffrax._root_finder._verychord import VeryChord

        return VeryChord(rtol=self.rtol, atol=self.atol, norm=self.norm, kappa=self.kappa, linear_solver=lx.LU())

    def init(self, fn, y, args, options, f_struct, aux_struct, tags):
        from diffrax._root_finder._verychord import _VeryChordState

        if "init_state" in options:
            return options["init_state"]
        J = dense_jacobian(lambda z: fn(z, args)[0], y, self.coloring)
        op = lx.MatrixLinearOperator(jax.lax.stop_gradient(J))
        lin_state = lx.LU().init(op, options={})
        return _VeryChordState(linear_state=(op, lin_state), diff=jnp.full(y.shape, jnp.inf, y.dtype),
                               diffsize=jnp.array(jnp.inf, y.dtype), diffsize_prev=jnp.array(1.0, y.dtype),
                               result=optx.RESULTS.successful, step=jnp.array(0))

    def step(self, fn, y, args, options, state, tags):
        return self._chord().step(fn, y, args, options, state, tags)

    def terminate(self, fn, y, args, options, state, tags):
        return self._chord().terminate(fn, y, args, options, state, tags)

    def postprocess(self, fn, y, aux, args, options, state, tags, result):
        return y, aux, {}


# -- the compiled chunk ---------------------------------------------------------------------------------------------


def _vf(t, y, args):
    params, omega0, accel = args
    return runup_vector_field(t, y, params, omega0, accel)


@functools.lru_cache(maxsize=16)
def _chunk_solver(solver: str, max_steps: int, save_states: bool, coloring: Coloring | None = None):
    """A jitted ``chunk(y0, t0, t1, ts, dt0, params, omega0, accel, h_rub, ctrl)`` for these static settings;
    ``ctrl = (rtol, atol, pcoeff, icoeff)`` are traced, so changing a tolerance does not recompile.

    Saves the rotor states and h_min (and the full state when ``save_states``) at ``ts`` and the full state at
    the end; stops at the rub event ``h_min = h_rub``.
    """
    term = dfx.ODETerm(_vf)

    @eqx.filter_jit
    def chunk(y0, t0, t1, ts, dt0, params, omega0, accel, h_rub, ctrl):
        rtol, atol, pcoeff, icoeff = ctrl
        if coloring is None:
            slv = SOLVERS[solver]()  # diffrax' VeryChord: dense jacfwd Jacobian + lineax AutoLinearSolver (LU)
        else:
            slv = SOLVERS[solver](root_finder=ColoredChord(rtol=rtol, atol=atol, coloring=coloring))
        controller = dfx.PIDController(rtol=rtol, atol=atol, pcoeff=pcoeff, icoeff=icoeff)
        def out_fn(t, y, args):
            r, hm = outputs_of(y, args[0])
            d = {"rotor": r, "h_min": hm}
            if save_states:
                d["state"] = y
            return d

        def cond_fn(t, y, args, **kwargs):
            return jnp.min(film(y, args[0])) - h_rub

        event = dfx.Event(cond_fn, root_finder=optx.Newton(rtol=1e-8, atol=1e-10))
        saveat = dfx.SaveAt(subs=[dfx.SubSaveAt(ts=ts, fn=out_fn), dfx.SubSaveAt(t1=True)])
        sol = dfx.diffeqsolve(term, slv, t0, t1, dt0, y0, args=(params, omega0, accel), saveat=saveat,
                              stepsize_controller=controller, event=event, max_steps=max_steps, throw=False)
        outs, yend = sol.ys
        return dict(outs=outs, ts=sol.ts[0], t_end=sol.ts[1][0], y_end=yend[0], result=sol.result._value,
                    event=jnp.any(jnp.asarray(sol.event_mask)), steps=sol.stats["num_steps"],
                    accepted=sol.stats["num_accepted_steps"], rejected=sol.stats["num_rejected_steps"])

    return chunk


def _h_min_of(y: np.ndarray, params: Params) -> float:
    return float(jnp.min(film(jnp.asarray(y), params)))


def _integrate(params: Params, y0: np.ndarray, omega0: float, accel: float, tau_end: float, dtau: float,
               settings: TransientSettings, progress: bool, desc: str, note: str,
               callback: Callable[[dict[str, Any]], None] | None = None) -> TransientResult:
    """Integrate from ``tau = 0`` to ``tau_end`` saving every ``dtau``, in chunks of ``settings.chunk_revs``."""
    from tqdm.auto import tqdm

    params = params.traced()
    lay = layout(params)
    y0 = np.asarray(y0, dtype=np.float64)
    if y0.shape != (lay.n_core,):
        raise ParameterError(f"initial state has shape {y0.shape}; this system needs ({lay.n_core},)")
    if not np.all(np.isfinite(y0)):
        raise ParameterError("initial state has non-finite entries")
    n_total = int(math.floor(tau_end / dtau + 1e-9))
    grid = np.arange(n_total + 1) * dtau  # global save times; tau_end snapped to a sample
    if grid[-1] < tau_end - 1e-12 * max(1.0, tau_end):
        grid = np.append(grid, tau_end)
        n_total += 1
    m = max(1, int(round(settings.chunk_revs * settings.samples_per_rev)))
    n_chunks = max(1, math.ceil(n_total / m))
    ctrl = tuple(jnp.asarray(float(v)) for v in (settings.rtol, settings.atol, settings.pcoeff, settings.icoeff))
    chunk = _chunk_solver(settings.solver, settings.max_steps_per_chunk, settings.save_states,
                          jacobian_coloring(params) if settings.jacobian == "colored" else None)

    r0, h0 = outputs_of(jnp.asarray(y0), params)
    taus = [grid[:1]]
    rotors = [np.asarray(r0)[None]]
    hmins = [np.asarray(h0)[None]]
    states = [y0[None]] if settings.save_states else None
    y, dt0 = jnp.asarray(y0), dtau / 8.0  # first step; later chunks start with the previous mean step
    steps = accepted = rejected = 0
    outcome, message = Outcome.COMPLETED, ""
    chunk_times: list[float] = []
    t_wall = time.perf_counter()
    t_cpu = time.process_time()
    omega0_a, accel_a, hrub_a = (jnp.asarray(v, dtype=jnp.float64) for v in (omega0, accel, settings.h_rub))
    if float(h0) <= settings.h_rub:
        outcome = Outcome.RUB
        message = f"the initial state already touches: h_min = {float(h0):.4g} c <= h_rub = {settings.h_rub:g} c"
        n_chunks = 0
    bar = tqdm(total=n_chunks, desc=desc, unit="chunk", disable=not progress, file=sys.stderr, dynamic_ncols=True)
    try:
        for c in range(n_chunks):
            i0, i1 = c * m, min((c + 1) * m, n_total)
            t0, t1 = float(grid[i0]), float(grid[i1])
            ts = grid[i0 + 1: i1 + 1]
            ts = np.concatenate([ts, np.full(m - ts.size, t1)])  # fixed length: compile once
            tc = time.perf_counter()
            out = chunk(y, jnp.asarray(t0), jnp.asarray(t1), jnp.asarray(ts),
                        jnp.asarray(dt0), params, omega0_a, accel_a, hrub_a, ctrl)
            out = jax.device_get(out)
            chunk_times.append(time.perf_counter() - tc)
            steps += int(out["steps"])
            accepted += int(out["accepted"])
            rejected += int(out["rejected"])
            n_valid = i1 - i0
            ts_got = np.asarray(out["ts"])[:n_valid]
            rot = np.asarray(out["outs"]["rotor"])[:n_valid]
            hm = np.asarray(out["outs"]["h_min"])[:n_valid]
            st = np.asarray(out["outs"]["state"])[:n_valid] if settings.save_states else None
            ok = np.isfinite(ts_got) & np.all(np.isfinite(rot), axis=1) & np.isfinite(hm)
            if st is not None:
                ok &= np.all(np.isfinite(st), axis=1)
            k = int(np.argmin(ok)) if not ok.all() else n_valid  # keep the leading finite samples
            taus.append(ts_got[:k])
            rotors.append(rot[:k])
            hmins.append(hm[:k])
            if states is not None:
                states.append(st[:k])
            y_end = np.asarray(out["y_end"])
            t_end = float(out["t_end"])
            result = int(out["result"])
            if bool(out["event"]):
                if np.all(np.isfinite(y_end)):  # the contact state itself, at the event time
                    r_e, h_e = outputs_of(jnp.asarray(y_end), params)
                    if t_end > (taus[-1][-1] if taus[-1].size else t0):
                        taus.append(np.array([t_end]))
                        rotors.append(np.asarray(r_e)[None])
                        hmins.append(np.asarray(h_e)[None])
                        if states is not None:
                            states.append(y_end[None])
                    y = jnp.asarray(y_end)
                outcome = Outcome.RUB
                message = (f"rub: the film thickness reached h_min = {settings.h_rub:g} c at tau = {t_end:.6g}, "
                           f"Omega_bar = {omega0 + accel * t_end:.5g}")
                bar.update(1)
                break
            if result != 0 or not np.all(np.isfinite(y_end)) or k < n_valid:
                last_h = float(hmins[-1][-1]) if hmins[-1].size else float(np.concatenate(hmins)[-1])
                t_last = float(np.concatenate(taus)[-1])
                reason = _result_name(result)
                if last_h < 5 * max(settings.h_rub, 0.01):
                    outcome = Outcome.RUB
                    message = (f"rub: the solver stalled ({reason}) with the film nearly closed, h_min = {last_h:.3g} c "
                               f"at tau = {t_last:.6g}, Omega_bar = {omega0 + accel * t_last:.5g}")
                else:
                    outcome = Outcome.INTEGRATION_FAILED
                    message = (f"solver failure ({reason}) in chunk {c + 1}/{n_chunks}; samples kept up to "
                               f"tau = {t_last:.6g} (Omega_bar = {omega0 + accel * t_last:.5g})")
                if k == n_valid and np.all(np.isfinite(y_end)):
                    y = jnp.asarray(y_end)
                else:  # state at the last kept sample is unknown unless saved; keep the chunk start
                    y = jnp.asarray(states[-1][-1]) if states is not None and states[-1].size else y
                bar.update(1)
                break
            y = jnp.asarray(y_end)
            n_acc = max(1, int(out["accepted"]))
            dt0 = (t1 - t0) / n_acc  # mean step of this chunk starts the next one
            bar.update(1)
            if progress or callback is not None:
                info = {"chunk": c + 1, "chunks": n_chunks, "tau": t1, "speed": omega0 + accel * t1,
                        "h_min": float(hm[:k].min()) if k else float("nan"), "steps": steps}
                bar.set_postfix_str(f"Omega={info['speed']:.4f} h_min={info['h_min']:.3f} steps={steps}")
                if callback is not None:
                    callback(info)
    except KeyboardInterrupt:
        outcome, message = Outcome.INTERRUPTED, "interrupted by the user; samples kept up to the last finished chunk"
    finally:
        bar.close()
    wall = time.perf_counter() - t_wall
    cpu = time.process_time() - t_cpu
    tau = np.concatenate(taus)
    rotor = np.concatenate(rotors)
    hmin = np.concatenate(hmins)
    speed = omega0 + accel * tau
    if outcome is Outcome.COMPLETED:
        message = f"completed {tau[-1]:.6g} tau ({_revs(omega0, accel, tau[-1]):.1f} revolutions)"
    if note:
        message = f"{message}; {note}"
    compile_s = (chunk_times[0] - float(np.mean(chunk_times[1:]))) if len(chunk_times) > 1 else None
    revs = _revs(omega0, accel, float(tau[-1]))
    stats = {"steps": steps, "accepted": accepted, "rejected": rejected, "wall_s": wall, "cpu_s": cpu, "compile_s": compile_s,
             "chunks": len(chunk_times), "chunk_wall_s": chunk_times,
             "steps_per_s": steps / wall if wall > 0 else None, "revs_per_s": revs / wall if wall > 0 else None}
    run_time = wall - (compile_s or 0.0)
    if compile_s is not None and run_time > 0:
        stats["steps_per_s_excl_compile"] = steps / run_time
        stats["revs_per_s_excl_compile"] = revs / run_time
    return TransientResult(
        tau=tau, speed=speed, rotor=rotor, h_min=hmin, final_state=np.asarray(y), outcome=outcome,
        message=message, omega0=float(omega0), accel=float(accel), samples_per_rev=settings.samples_per_rev,
        rotor_kind=params.rotor, stats=stats, settings=dataclasses.asdict(settings),
        states=None if states is None else np.concatenate(states))


def _revs(omega0: float, accel: float, tau: float) -> float:
    return abs(omega0 * tau + 0.5 * accel * tau**2) / (2 * math.pi)


def _result_name(code: int) -> str:
    """diffrax' name of a result code (e.g. ``max_steps_reached``)."""
    try:
        for name, item in dfx.RESULTS._name_to_item.items():
            if int(item._value) == code:
                return name
    except Exception:  # noqa: BLE001 - private diffrax API; fall back to the number
        pass
    return f"diffrax result code {code}"


# -- public entry points -----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RunPlan:
    """A checked transient run: start speed ``omega0``, acceleration ``accel`` (0 at constant speed), length
    ``tau_end`` and sample spacing ``dtau`` (dimensionless)."""

    omega0: float
    accel: float
    tau_end: float
    dtau: float


def _check_history(params: Params, plan: RunPlan, settings: TransientSettings, what: str) -> None:
    """Refuse a run whose saved samples would not fit in memory (:func:`gfbjax.limits.check_history`): per sample
    the time, speed, h_min and rotor states, and the full state with ``save_states``."""
    lay = layout(params)
    per_sample = 8 * (lay.n_rotor + 3 + (lay.n_core if settings.save_states else 0))
    limits.check_history(plan.tau_end / plan.dtau + 1, per_sample, what)


def check_simulate(params: Params, omega: Any, *, revolutions: Any = None, tau_end: Any = None,
                   settings: TransientSettings | None = None) -> RunPlan:
    """Check the inputs of :func:`simulate` before any computation and return its :class:`RunPlan`.

    ``params`` by :meth:`Params.check`; ``omega`` in :data:`gfbjax.limits.SPEED`; ``revolutions`` (default 100) in
    :data:`~gfbjax.limits.REVOLUTIONS`, or ``tau_end`` > 0; the samples within
    :data:`~gfbjax.limits.MAX_HISTORY_BYTES`.
    """
    settings = settings or TransientSettings()
    check_params(params)
    omega = limits.SPEED.check(omega, "omega")
    period = 2 * math.pi / omega
    if tau_end is None:
        revolutions = limits.REVOLUTIONS.check(100.0 if revolutions is None else revolutions)
        tau_end = revolutions * period
    elif revolutions is not None:
        raise ParameterError("give either revolutions or tau_end, not both")
    else:
        tau_end = limits.Range("tau_end", 0.0, None, lo_open=True).check(tau_end)
    plan = RunPlan(omega, 0.0, tau_end, period / settings.samples_per_rev)
    _check_history(params, plan, settings, f"a run of {tau_end / period:.4g} revolutions")
    return plan


def check_run_up(params: Params, omega_start: Any, omega_end: Any, *, accel: Any = None, revolutions: Any = None,
                 settings: TransientSettings | None = None) -> RunPlan:
    """Check the inputs of :func:`run_up` before any computation and return its :class:`RunPlan`.

    Speeds in :data:`gfbjax.limits.SPEED` and different; either ``revolutions`` (default 300) in
    :data:`~gfbjax.limits.REVOLUTIONS`, or ``accel`` with ``|accel|`` in :data:`~gfbjax.limits.ACCEL`, the sign of
    ``omega_end - omega_start``, and implying at most as many revolutions; the samples within
    :data:`~gfbjax.limits.MAX_HISTORY_BYTES`.
    """
    settings = settings or TransientSettings()
    check_params(params)
    w0 = limits.SPEED.check(omega_start, "omega_start")
    w1 = limits.SPEED.check(omega_end, "omega_end")
    if w0 == w1:
        raise ParameterError("omega_end equals omega_start: use simulate() for a constant-speed run")
    if accel is None:
        accel = runup_acceleration(w0, w1, 300.0 if revolutions is None else revolutions)
    elif revolutions is not None:
        raise ParameterError("give either accel or revolutions, not both")
    else:
        accel = _check_accel(w0, w1, accel)
    tau_end = (w1 - w0) / accel
    plan = RunPlan(w0, accel, tau_end, 2 * math.pi / (max(w0, w1) * settings.samples_per_rev))
    _check_history(params, plan, settings, "the run-up")
    return plan


def _check_accel(w0: float, w1: float, accel: Any) -> float:
    """A run-up acceleration: non-zero, the sign of ``w1 - w0``, ``|accel|`` in :data:`gfbjax.limits.ACCEL`, and
    at most :data:`~gfbjax.limits.REVOLUTIONS` revolutions from ``w0`` to ``w1``."""
    a = limits.check_real("accel", accel)
    limits.ACCEL.check(abs(a), "|accel|")
    if (a > 0) != (w1 > w0):
        direction = "a run-up" if w1 > w0 else "a coast-down"
        raise ParameterError(f"accel = {a:g} has the wrong sign: Omega_bar {w0:g} -> {w1:g} is {direction}, so "
                             f"accel must be {'positive' if w1 > w0 else 'negative'}")
    revs = abs(w1**2 - w0**2) / (4.0 * math.pi * abs(a))
    if not limits.REVOLUTIONS.contains(revs):
        raise ParameterError(f"accel = {a:g} per tau^2 implies {revs:.3g} revolutions from Omega_bar {w0:g} to "
                             f"{w1:g}, outside the allowed range {limits.REVOLUTIONS.interval()} (a larger |accel|)")
    return a


def simulate(params: Params, omega: float, *, revolutions: float | None = None, tau_end: float | None = None,
             s0: np.ndarray | Array | None = None, settings: TransientSettings | None = None,
             progress: bool = False, callback: Callable[[dict[str, Any]], None] | None = None
             ) -> TransientResult:
    """Integrate the unbalanced system at constant speed ``omega`` (Eq. 17 with Eq. 15a).

    Args:
        params: dimensionless system (``SystemSpec.nondim()``).
        omega: speed Omega_bar in (0, 50] (:data:`gfbjax.limits.SPEED`).
        revolutions: length of the run in revolutions (default 100), in (0, 1e6]; or give ``tau_end``.
        tau_end: length of the run in dimensionless time tau (instead of ``revolutions``).
        s0: core state to start from; default the static equilibrium of the balanced system at ``omega``.
        settings: :class:`TransientSettings` (default: Kvaerno5, rtol 1e-6, atol 1e-8, 32 samples per rev).
        progress: show a tqdm progress bar advanced per chunk.
        callback: called after each chunk with ``{chunk, chunks, tau, speed, h_min, steps}``.

    Returns:
        :class:`TransientResult`; samples at ``tau = k T / N`` (``T = 2 pi / omega``, ``N = samples_per_rev``), so
        every N-th sample lies on the Poincare section (phase 0): :meth:`TransientResult.poincare`.
    """
    settings = settings or TransientSettings()
    plan = check_simulate(params, omega, revolutions=revolutions, tau_end=tau_end, settings=settings)
    omega = plan.omega0
    note = ""
    if s0 is None:
        s0, note = default_initial_state(params, omega)
    return _integrate(params, np.asarray(s0), omega, 0.0, plan.tau_end, plan.dtau, settings,
                      progress, f"Omega={omega:g}", note, callback)


def run_up(params: Params, omega_start: float, omega_end: float, *, accel: float | None = None,
           revolutions: float | None = None, s0: np.ndarray | Array | None = None,
           settings: TransientSettings | None = None, progress: bool = False,
           callback: Callable[[dict[str, Any]], None] | None = None) -> TransientResult:
    """Run-up (``omega_end > omega_start``) or coast-down at constant angular acceleration (Eq. 15b).

    ``Omega(tau) = omega_start + accel tau``; unbalance phase ``omega_start tau + accel tau^2 / 2``.

    Args:
        params: dimensionless system.
        omega_start, omega_end: speed range, Omega_bar in (0, 50] (:data:`gfbjax.limits.SPEED`).
        accel: angular acceleration ``a_bar`` per tau^2 (its sign must match the direction), ``|accel|`` in
            (0, 100] and implying at most 1e6 revolutions; or give
        revolutions: revolutions from start to end (default 300), in (0, 1e6], which set ``accel`` by
            :func:`runup_acceleration`.

    Every input is checked before any computation (:func:`check_run_up`), the memory of the saved samples too.
        s0: start state; default the static equilibrium of the balanced system at ``omega_start``.
        settings: :class:`TransientSettings`; samples are uniform in tau, ``samples_per_rev`` per revolution at
            the higher of the two speeds.
        progress: tqdm progress bar per chunk.
        callback: called after each chunk.
    """
    settings = settings or TransientSettings()
    plan = check_run_up(params, omega_start, omega_end, accel=accel, revolutions=revolutions, settings=settings)
    w0 = plan.omega0
    note = ""
    if s0 is None:
        s0, note = default_initial_state(params, w0)
    kind = "run-up" if plan.accel > 0 else "coast-down"
    return _integrate(params, np.asarray(s0), w0, plan.accel, plan.tau_end, plan.dtau, settings, progress, kind,
                      note, callback)
