"""The analyses a sweep runs on each design, each a small frozen dataclass: its settings (checked when it is built),
the figures it returns (flat numbers or short texts, with units) and ``run(spec)``.

A figure is either one value per design or, for the analyses at given speeds (``static``, ``energy``,
``optimum``), one value per speed; the sweep's Dataset gives those the extra dimension ``<analysis>_omega_bar``.
Numbers that do not exist for a design (no Hopf point in the range, a cycle that did not converge at one speed) are
NaN and the reason is in a text figure next to them (``*_outcome``); an analysis that raises is reported by the
sweep as a failed design (``outcome``/``message``), never as a silent blank.

Settings are part of the stored results' identity (``settings()``), so every field that changes a number is a field
of the dataclass.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar, Sequence

import numpy as np

from .. import limits
from ..analyses.cycles import CYCLE_DEFAULTS
from ..limits import NoSolutionError, ParameterError
from ..params import SystemSpec

__all__ = ["Figure", "Analysis", "Static", "Equilibria", "Cycles", "Energy", "Optimum", "ANALYSES",
           "make_analyses"]


@dataclass(frozen=True)
class Figure:
    """One result of an analysis: ``name`` (the Dataset variable), ``units``, ``long_name``; ``per_speed`` (one value
    per speed of the analysis) and ``text`` (a string, ``""`` where undefined; otherwise a float, NaN where
    undefined; flags are 1.0 / 0.0)."""

    name: str
    units: str
    long_name: str
    per_speed: bool = False
    text: bool = False


class Analysis:
    """Base of the sweep analyses (frozen dataclasses, picklable, so that Dask ships them to its workers)."""

    name: ClassVar[str] = ""
    figures: ClassVar[tuple[Figure, ...]] = ()

    @property
    def speeds(self) -> tuple[float, ...]:
        """The speeds (Omega_bar) of the per-speed figures; empty for the analyses over a speed range."""
        return ()

    def settings(self) -> dict[str, Any]:
        """Every setting as JSON values, with ``"analysis": name`` (part of a stored design's identity)."""
        d = {"analysis": self.name}
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            d[f.name] = list(v) if isinstance(v, tuple) else v
        return d

    def check(self, specs: Sequence[SystemSpec], labels: Sequence[str]) -> None:
        """ParameterError when a design cannot be analysed at all (checked for every design before any work);
        ``labels`` name the designs in the message."""

    def run(self, spec: SystemSpec) -> dict[str, Any]:  # pragma: no cover - abstract
        raise NotImplementedError


def _speeds(label: str, values: Any) -> tuple[float, ...]:
    if isinstance(values, (int, float, np.number)):
        values = (values,)
    try:
        out = tuple(limits.SPEED.check(v, label) for v in values)
    except TypeError:
        raise ParameterError(f"{label} must be a list of speeds Omega_bar, got {values!r}") from None
    if not out:
        raise ParameterError(f"{label} needs at least one speed")
    if len(set(out)) != len(out):
        raise ParameterError(f"{label} = {list(out)} repeats a speed")
    return out


def _range(obj: Any) -> None:
    limits.SPEED.check(obj.start, f"{obj.name}.start")
    limits.SPEED.check(obj.end, f"{obj.name}.end")
    if obj.start == obj.end:
        raise ParameterError(f"{obj.name}.end must differ from {obj.name}.start = {obj.start:g}")


def _count(label: str, value: Any, lo: int, hi: int) -> int:
    return limits.Range(label, lo, hi, integer=True).check(value)


def _flag(v: bool | None) -> float:
    return math.nan if v is None else (1.0 if v else 0.0)


def _settings_error(name: str, exc: ValueError) -> ParameterError:
    return ParameterError(f"{name}: {exc}")


def _need_unbalance(name: str, specs: Sequence[SystemSpec], labels: Sequence[str]) -> None:
    for spec, label in zip(specs, labels):
        if spec.eccentricity_u <= 0.0:
            raise ParameterError(f"{label}: the {name} analysis needs an unbalanced rotor (G > 0 or e_u > 0); this "
                                 "design is balanced (eps = 0), it has no forced cycle")


def _check_cycle_size(name: str, specs: Sequence[SystemSpec], m: int, N: int) -> None:
    """The engine's memory and Floquet checks, once per state layout (grid, rotor model and axial domain: the only
    parts of a spec they depend on)."""
    from .. import cont
    from ..analyses.cycles import gfb_cycle_problem

    done = set()
    for spec in specs:
        key = (spec.Nx, spec.Nz, spec.rotor, spec.axial_domain)
        if key in done:
            continue
        done.add(key)
        try:
            cont.check_cycle_size(gfb_cycle_problem(spec.nondim()), N, m, cont.CycleSettings(m=m, N=N))
        except ValueError as exc:
            raise ParameterError(f"{name}: {exc}") from None


# -- static ------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Static(Analysis):
    """The static equilibrium at each of ``speeds`` (Omega_bar) under gravity plus the extra specific load ``w``
    (``W/(p0 L D)`` per bearing), each solved from the centred state
    (:func:`gfbjax.analyses.static.solve_equilibrium`)."""

    speeds: tuple[float, ...] = (0.3,)  # type: ignore[assignment]
    w: float = 0.0

    name: ClassVar[str] = "static"
    figures: ClassVar[tuple[Figure, ...]] = (
        Figure("static_eccentricity", "over clearance c", "journal eccentricity of the static equilibrium", True),
        Figure("static_attitude_deg", "deg", "attitude angle from the load line, in the direction of rotation", True),
        Figure("static_h_min", "over clearance c", "minimum film thickness", True),
        Figure("static_h_min_um", "um", "minimum film thickness", True),
        Figure("static_stable", "1 = stable, 0 = unstable", "linear stability of the equilibrium", True),
        Figure("static_outcome", "", "outcome of the static solve (converged, contact, no_solution)", True, True),
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "speeds", _speeds("static.speeds", self.speeds))
        object.__setattr__(self, "w", limits.LOAD_W.check(self.w, "static.w"))

    def run(self, spec: SystemSpec) -> dict[str, Any]:
        from ..analyses.static import solve_equilibrium

        params = spec.nondim().traced()
        cols: dict[str, list[Any]] = {f.name: [] for f in self.figures}
        for omega in self.speeds:
            r = solve_equilibrium(params, omega, self.w)
            ok = r.converged  # a partly loaded state (contact) would read as a real equilibrium
            cols["static_eccentricity"].append(r.eccentricity if ok else math.nan)
            cols["static_attitude_deg"].append(r.attitude_deg if ok else math.nan)
            cols["static_h_min"].append(r.h_min if ok else math.nan)
            cols["static_h_min_um"].append(r.h_min * spec.c * 1e6 if ok else math.nan)
            cols["static_stable"].append(_flag(r.stable) if ok else math.nan)
            cols["static_outcome"].append(str(r.outcome))
        return cols


# -- equilibria ---------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Equilibria(Analysis):
    """The branch of equilibria of the balanced rotor from ``start`` to ``end`` (Omega_bar) with its first Hopf
    point (:func:`gfbjax.analyses.cycles.continue_gfb_equilibria`); continuation settings as
    :class:`gfbjax.cont.EquilibriumSettings`.  ``criticality_points`` > 0 also continues the self-excited cycles
    from a located Hopf point for that many points (collocation ``hopf_N`` x ``hopf_m``) to tell sub- from
    supercritical (:func:`gfbjax.analyses.cycles.hopf_criticality`); it costs a cycle continuation per design."""

    start: float = 0.05
    end: float = 1.0
    ds: float = 0.05
    ds_max: float = 0.5
    max_points: int = 200
    locate: bool = True
    criticality_points: int = 0
    hopf_N: int = 16
    hopf_m: int = 4

    name: ClassVar[str] = "equilibria"
    figures: ClassVar[tuple[Figure, ...]] = (
        Figure("hopf_omega_bar", "Omega_bar = Omega t*", "speed of the first Hopf point (onset of whirl); NaN: none "
               "in the range"),
        Figure("hopf_rpm", "rpm", "speed of the first Hopf point"),
        Figure("hopf_whirl_omega", "per tau", "whirl frequency at the first Hopf point (imaginary part of the "
               "critical eigenvalue)"),
        Figure("hopf_whirl_ratio", "", "whirl frequency over running speed at the first Hopf point"),
        Figure("hopf_frequency_hz", "Hz", "whirl frequency at the first Hopf point"),
        Figure("hopf_located", "1 = located, 0 = bracketed only", "whether the first Hopf point was located"),
        Figure("hopf_count", "", "number of Hopf points on the branch"),
        Figure("hopf_criticality", "", "sub- or supercritical (from the self-excited cycles; '' when not computed)",
               text=True),
        Figure("equilibria_stable_at_start", "1 = stable, 0 = unstable", "stability of the first equilibrium"),
        Figure("equilibria_last_omega_bar", "Omega_bar = Omega t*", "speed of the last point of the branch"),
        Figure("equilibria_points", "", "points on the branch"),
        Figure("equilibria_outcome", "", "why the branch ended (gfbjax.cont.Outcome)", text=True),
    )

    def __post_init__(self) -> None:
        _range(self)
        _count("equilibria.criticality_points", self.criticality_points, 0, 10**5)
        if self.criticality_points:
            limits.MESH_N.check(self.hopf_N, "equilibria.hopf_N")
            limits.COLLOCATION_M.check(self.hopf_m, "equilibria.hopf_m")
        self.cont_settings()

    def cont_settings(self):
        from .. import cont

        try:
            return cont.EquilibriumSettings(ds=self.ds, ds_max=self.ds_max, max_points=self.max_points,
                                            locate=self.locate)
        except ValueError as exc:
            raise _settings_error("equilibria", exc) from None

    def run(self, spec: SystemSpec) -> dict[str, Any]:
        from ..analyses.cycles import continue_gfb_equilibria

        params = spec.nondim().traced()
        br = continue_gfb_equilibria(params, self.start, self.end, self.cont_settings(), spec=spec)
        hopfs = sorted(br.special_of("HOPF"), key=lambda s: s.index)
        out: dict[str, Any] = {f.name: ("" if f.text else math.nan) for f in self.figures}
        out.update(hopf_count=float(len(hopfs)), equilibria_points=float(len(br)),
                   equilibria_outcome=str(br.outcome))
        if len(br):
            out["equilibria_stable_at_start"] = _flag(bool(br.stable[0]))
            out["equilibria_last_omega_bar"] = float(br.lam[-1])
        if hopfs:
            h = hopfs[0]
            lam = float(h.lam)
            out.update(hopf_omega_bar=lam, hopf_rpm=spec.rpm(lam), hopf_located=_flag(h.located))
            if h.omega is not None:
                w = abs(float(h.omega))
                out.update(hopf_whirl_omega=w, hopf_whirl_ratio=w / lam,
                           hopf_frequency_hz=w / spec.t_star / (2 * math.pi))
            if self.criticality_points:
                out["hopf_criticality"] = self._criticality(params, spec, br, h)
        return out

    def _criticality(self, params: Any, spec: SystemSpec, br: Any, hopf: Any) -> str:
        from ..analyses.cycles import continue_gfb_hopf_cycles, default_cycle_settings, hopf_criticality

        if not hopf.located:  # its state is no Hopf point: the cycles could not start from it
            return "undetermined (Hopf point not located)"
        lo, hi = sorted((self.start, self.end))
        s = default_cycle_settings(m=self.hopf_m, N=self.hopf_N, ds=0.02, ds_max=2.0, dlam_max=0.005,
                                   max_points=self.criticality_points, lam_min=lo, lam_max=hi)
        cyc = continue_gfb_hopf_cycles(params, br, 0, s, spec=spec)
        return hopf_criticality(cyc, float(hopf.lam))


# -- cycles -------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Cycles(Analysis):
    """The branch of unbalance-response cycles from ``start`` to ``end`` (Omega_bar) with Floquet stability and its
    LPC/PD/NS points (:func:`gfbjax.analyses.cycles.continue_gfb_cycles`); settings as
    :func:`gfbjax.analyses.cycles.default_cycle_settings` (``m`` collocation points on ``N`` intervals)."""

    start: float = 0.05
    end: float = 1.0
    m: int = CYCLE_DEFAULTS["m"]
    N: int = CYCLE_DEFAULTS["N"]
    ds: float = CYCLE_DEFAULTS["ds"]
    ds_max: float = CYCLE_DEFAULTS["ds_max"]
    dlam_max: float = CYCLE_DEFAULTS["dlam_max"]
    chord_tol: float = CYCLE_DEFAULTS["chord_tol"]
    max_points: int = CYCLE_DEFAULTS["max_points"]
    locate: bool = True

    name: ClassVar[str] = "cycles"
    figures: ClassVar[tuple[Figure, ...]] = (
        Figure("cycles_loss_omega_bar", "Omega_bar = Omega t*", "first loss of stability of the cycles (the special "
               "point there when one was found, else the first unstable point; the start speed when the first "
               "cycle is unstable; NaN: stable over the branch)"),
        Figure("cycles_loss_rpm", "rpm", "first loss of stability of the cycles"),
        Figure("cycles_stable_at_start", "1 = stable, 0 = unstable", "stability of the first cycle"),
        Figure("cycles_first_special", "", "type of the first special point (LPC, PD, NS; '' none)", text=True),
        Figure("cycles_first_special_omega_bar", "Omega_bar = Omega t*", "speed of the first special point"),
        Figure("cycles_first_special_rpm", "rpm", "speed of the first special point"),
        Figure("cycles_special_count", "", "special points on the branch"),
        Figure("cycles_last_omega_bar", "Omega_bar = Omega t*", "speed of the last point of the branch"),
        Figure("cycles_points", "", "points on the branch"),
        Figure("cycles_flagged", "", "points whose trivial multiplier is off +1 by more than trivial_tol "
               "(unreliable stability labels: refine N)"),
        Figure("cycles_outcome", "", "why the branch ended (gfbjax.cont.Outcome)", text=True),
    )

    def __post_init__(self) -> None:
        _range(self)
        self.cont_settings()

    def cont_settings(self):
        from ..analyses.cycles import default_cycle_settings

        limits.COLLOCATION_M.check(self.m, "cycles.m")
        limits.MESH_N.check(self.N, "cycles.N")
        try:
            return default_cycle_settings(m=self.m, N=self.N, ds=self.ds, ds_min=min(1e-4, self.ds),
                                          ds_max=self.ds_max, dlam_max=self.dlam_max, chord_tol=self.chord_tol,
                                          max_points=self.max_points,
                                          locate=self.locate)
        except ValueError as exc:
            raise _settings_error("cycles", exc) from None

    def check(self, specs: Sequence[SystemSpec], labels: Sequence[str]) -> None:
        _need_unbalance(self.name, specs, labels)
        _check_cycle_size(self.name, specs, self.m, self.N)

    def run(self, spec: SystemSpec) -> dict[str, Any]:
        from ..analyses.cycles import continue_gfb_cycles

        br = continue_gfb_cycles(spec.nondim().traced(), self.start, self.end, self.cont_settings(), spec=spec)
        return cycle_branch_figures(br, spec)


def cycle_branch_figures(br: Any, spec: SystemSpec) -> dict[str, Any]:
    """The :class:`Cycles` figures of a cycle branch (see there)."""
    out: dict[str, Any] = {f.name: ("" if f.text else math.nan) for f in Cycles.figures}
    special = sorted((s for s in br.special if s.type in ("LPC", "PD", "NS", "BPC")), key=lambda s: s.index)
    out.update(cycles_special_count=float(len(special)), cycles_points=float(len(br)),
               cycles_outcome=str(br.outcome), cycles_flagged=float(np.sum(br.flagged)))
    if special:
        s = special[0]
        out.update(cycles_first_special=s.type, cycles_first_special_omega_bar=float(s.lam),
                   cycles_first_special_rpm=spec.rpm(float(s.lam)))
    if not len(br):
        return out
    lam = np.asarray(br.lam, float)
    stable = np.asarray(br.stable, bool)
    out["cycles_last_omega_bar"] = float(lam[-1])
    out["cycles_stable_at_start"] = _flag(bool(stable[0]))
    unstable = np.flatnonzero(~stable)
    if unstable.size:
        i = int(unstable[0])
        # a located special point is a row of the branch, flagged either way; prefer its speed to the row after it
        at = [s for s in special if i - 1 <= s.index <= i] if i > 0 else []
        loss = float(at[0].lam) if at else float(lam[i])
        out.update(cycles_loss_omega_bar=loss, cycles_loss_rpm=spec.rpm(loss))
    return out


# -- energy -------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Energy(Analysis):
    """W_cb, W_cf and W_fu [p0 R L c] of the unbalance-response cycle at each of ``speeds`` (Omega_bar), with its
    stability (:func:`gfbjax.analyses.energy.branch_energy`).  Each cycle is the first point of a continuation
    started at that speed (:func:`gfbjax.analyses.cycles.continue_gfb_cycles` for one point): the linear forced
    response corrected by collocation Newton on ``N`` intervals of ``m`` points.  The same compiled kernels serve
    this analysis and :class:`Cycles` with the same ``m`` and ``N``."""

    speeds: tuple[float, ...] = (0.3,)  # type: ignore[assignment]
    m: int = 4
    N: int = 16

    name: ClassVar[str] = "energy"
    figures: ClassVar[tuple[Figure, ...]] = (
        Figure("energy_W_cb", "p0 R L c", "net energy dissipated by the gas films per cycle", True),
        Figure("energy_W_cf", "p0 R L c", "energy dissipated by the bump-foil dampers per cycle", True),
        Figure("energy_W_fu", "p0 R L c", "work of the unbalance force per cycle", True),
        Figure("energy_max_mu", "", "largest non-trivial Floquet multiplier modulus", True),
        Figure("energy_stable", "1 = stable, 0 = unstable", "stability of the cycle", True),
        Figure("energy_outcome", "", "outcome of the cycle solve (converged, or why not)", True, True),
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "speeds", _speeds("energy.speeds", self.speeds))
        limits.COLLOCATION_M.check(self.m, "energy.m")
        limits.MESH_N.check(self.N, "energy.N")

    def check(self, specs: Sequence[SystemSpec], labels: Sequence[str]) -> None:
        _need_unbalance(self.name, specs, labels)
        _check_cycle_size(self.name, specs, self.m, self.N)

    def run(self, spec: SystemSpec) -> dict[str, Any]:
        from .. import cont
        from ..analyses.cycles import continue_gfb_cycles, default_cycle_settings
        from ..analyses.energy import branch_energy

        params = spec.nondim().traced()
        settings = default_cycle_settings(m=self.m, N=self.N, max_points=1, save_states=True)
        cols: dict[str, list[Any]] = {f.name: [] for f in self.figures}
        for omega in self.speeds:
            # the end only orients a branch of one point; below SPEED's cap there is room above any speed
            end = omega * 1.01 if omega * 1.01 <= limits.SPEED.hi else omega * 0.99
            try:
                br = continue_gfb_cycles(params, omega, end, settings)
                why = f"{br.outcome}: {br.message}"
            except NoSolutionError as exc:
                br, why = None, f"no_solution: {exc}"
            if br is None or not len(br):
                for f in self.figures:
                    cols[f.name].append(why if f.text else math.nan)
                continue
            W = branch_energy(br, params)
            nt = cont.nontrivial(np.asarray(br.multipliers[0]), 1)
            cols["energy_W_cb"].append(float(W.W_cb[0]))
            cols["energy_W_cf"].append(float(W.W_cf[0]))
            cols["energy_W_fu"].append(float(W.W_fu[0]))
            cols["energy_max_mu"].append(float(np.max(np.abs(nt))))
            cols["energy_stable"].append(_flag(bool(br.stable[0])))
            cols["energy_outcome"].append("converged")
        return cols


# -- optimum ------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Optimum(Analysis):
    """The foil optimum (alpha_f, eta) at each of ``speeds`` (Omega_bar), from the design's own foil
    (:func:`gfbjax.design.schedule.optimize_at_speed`): ``objective`` ``"W_cb"`` (maximise the films' dissipation)
    or ``"max_mu"`` (minimise the largest Floquet multiplier); ``method`` ``"gradient"``, ``"adam"`` or
    ``"pattern"``; at most ``max_iter`` optimiser iterations; cycles on ``N`` intervals of ``m`` points.  The
    design's own alpha_f and eta must lie inside the design bounds (paper Appendix A2)."""

    speeds: tuple[float, ...] = (0.3,)  # type: ignore[assignment]
    objective: str = "W_cb"
    method: str = "gradient"
    max_iter: int = 50
    m: int = 4
    N: int = 16

    name: ClassVar[str] = "optimum"
    figures: ClassVar[tuple[Figure, ...]] = (
        Figure("optimum_alpha_f", "", "optimal bump-foil compliance", True),
        Figure("optimum_eta", "", "optimal foil loss factor", True),
        Figure("optimum_W_cb", "p0 R L c", "W_cb of the optimal foil's cycle", True),
        Figure("optimum_max_mu", "", "largest non-trivial Floquet multiplier modulus of the optimal foil's cycle",
               True),
        Figure("optimum_stable", "1 = stable, 0 = unstable", "stability of the optimal foil's cycle", True),
        Figure("optimum_solves", "", "limit-cycle solves spent", True),
        Figure("optimum_reason", "", "why the optimiser stopped (or why it failed)", True, True),
    )

    def __post_init__(self) -> None:
        from ..design.schedule import METHODS, OBJECTIVES

        object.__setattr__(self, "speeds", _speeds("optimum.speeds", self.speeds))
        if self.objective not in OBJECTIVES:
            raise ParameterError(f"optimum.objective = {self.objective!r} is not one of {OBJECTIVES}")
        if self.method not in METHODS:
            raise ParameterError(f"optimum.method = {self.method!r} is not one of {METHODS}")
        _count("optimum.max_iter", self.max_iter, 1, 10**4)
        limits.COLLOCATION_M.check(self.m, "optimum.m")
        limits.MESH_N.check(self.N, "optimum.N")

    def check(self, specs: Sequence[SystemSpec], labels: Sequence[str]) -> None:
        from ..design.evaluate import check_foil

        _need_unbalance(self.name, specs, labels)
        for spec, label in zip(specs, labels):
            try:
                check_foil(spec.alpha_f, spec.eta)
            except ParameterError as exc:
                raise ParameterError(f"{label}: the optimum starts from the design's foil, which must lie inside "
                                     f"the design bounds: {exc}") from None
        _check_cycle_size(self.name, specs, self.m, self.N)

    def run(self, spec: SystemSpec) -> dict[str, Any]:
        from ..design.evaluate import FoilDesign
        from ..design.schedule import optimize_at_speed

        params = spec.nondim().traced()
        cols: dict[str, list[Any]] = {f.name: [] for f in self.figures}
        for omega in self.speeds:
            try:
                design = FoilDesign(params, omega, m=self.m, N=self.N)
                opt = optimize_at_speed(design, self.objective, self.method, max_iter=self.max_iter)
            except NoSolutionError as exc:  # no equilibrium to start from, or no cycle at any evaluated foil
                for f in self.figures:
                    cols[f.name].append(f"no_solution: {exc}" if f.text else math.nan)
                continue
            ev = opt.evaluation
            cols["optimum_alpha_f"].append(float(opt.alpha_f))
            cols["optimum_eta"].append(float(opt.eta))
            cols["optimum_W_cb"].append(float(ev.W_cb))
            cols["optimum_max_mu"].append(float(ev.max_mu))
            cols["optimum_stable"].append(_flag(ev.stable))
            cols["optimum_solves"].append(float(opt.n_solves))
            cols["optimum_reason"].append(str(opt.reason))
        return cols


ANALYSES: dict[str, type[Analysis]] = {c.name: c for c in (Static, Equilibria, Cycles, Energy, Optimum)}


def make_analyses(items: Any) -> tuple[Analysis, ...]:
    """Analyses from names (default settings) or instances: ``"equilibria"``, ``["static", Cycles(N=8)]``,
    ``"equilibria,cycles"``.  ParameterError for an unknown name (naming the allowed ones), an empty list or one
    analysis given twice."""
    if isinstance(items, (str, Analysis)):
        items = [items]
    out: list[Analysis] = []
    for item in items:
        if isinstance(item, str):
            for name in (s.strip() for s in item.split(",") if s.strip()):
                if name not in ANALYSES:
                    raise ParameterError(f"analysis {name!r} is not one of {tuple(ANALYSES)}")
                out.append(ANALYSES[name]())
        elif isinstance(item, Analysis):
            out.append(item)
        else:
            raise ParameterError(f"analyses: expected a name in {tuple(ANALYSES)} or an analysis object "
                                 f"(gfbjax.sweep.Static(...), ...), got {item!r}")
    if not out:
        raise ParameterError(f"analyses: give at least one of {tuple(ANALYSES)}")
    names = [a.name for a in out]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ParameterError(f"analyses: {dup} given more than once (one instance of each analysis per sweep)")
    return tuple(out)
