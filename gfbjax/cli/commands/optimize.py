"""``gfbjax optimize``: design of the bump foil (compliance alpha_f, loss factor eta) for the unbalance-response
limit cycle, at one speed or along the speed by optimised continuation (paper Sect. 3.3, Appendix A2,
Figs. 16-19)."""

from __future__ import annotations

import argparse
import time
from ...limits import NoSolutionError
from typing import Any

from ... import limits
from ...params import ParameterError
from ._common import (add_speed_option, add_system_options, check_option, check_range, output_dir, resolve_speeds,
                      spec_from_args, speed_si, traced_params, work_unit_J, write_summary)

NAME = "optimize"

# gfbjax.design.schedule.OBJECTIVES and METHODS, spelled out so that building the parser does not import the optimisers
# (the tests check that the two agree)
OBJECTIVES = ("W_cb", "max_mu")
METHODS = ("gradient", "adam", "pattern")
DEFAULT_STEP = 0.025

DESCRIPTION = """\
Optimisation of the bump foil, compliance alpha_f and structural loss factor eta, for the synchronous (1X) limit
cycle of the unbalanced rotor (paper Sect. 3.3, Appendix A2), inside the paper's bounds alpha_f in {a},
eta in {e}.  Objectives (--objective):

  max_mu  minimise the largest non-trivial Floquet multiplier modulus (OBJ2; < 1: stable cycle),
  W_cb    maximise the net energy the gas films dissipate per cycle (OBJ1; the paper minimises 1/W_cb).

Methods (--method): gradient (projected quasi-Newton in log-variables with the exact implicit gradients of the
cycle), adam (optax Adam on bounded variables; for comparison), pattern (the paper's generalized pattern search).
Every cycle is solved by collocation Newton, warm-started from the previous one.

One speed (--speed): optimise there from --x0.  Writes optimum.json (the optimum alpha_f, eta, the objective
value, W_cb, max|mu|, stability, the number of cycle solves and gradients, time, why the optimiser stopped and the
history of evaluations) and optimum.png (objective per evaluation; the path in the (alpha_f, eta) plane).

Optimised continuation (--start, --end, --step): optimise at each speed from the previous optimum and cycle, then
step the speed; the march stops at the first speed whose optimised cycle is unstable (no admissible foil keeps it
stable) or where no cycle converges.  With --method gradient each speed starts from the optimum and cycle
extrapolated from the last optima and carries the optimiser's curvature model over (far fewer cycle solves;
gfbjax.design.predictor).  Writes schedule.json (per speed the optimum, W_cb, max|mu|, stability, the
journal orbit's extent and the multipliers; the last speed with a stable optimised cycle) and schedule.png
(paper Figs. 16-19).
Exit status: 0 on success (one speed: an optimum found; continuation: --end reached), 1 when no cycle converged
or the march ended early (everything computed is still written), 2 for invalid input.
""".format(a=limits.DESIGN_ALPHA_F.interval(), e=limits.DESIGN_ETA.interval())

EPILOG = """\
units: speeds are dimensionless, Omega_bar = Omega t* (the bearing number); W_cb in p0 R L c per cycle;
alpha_f and eta are dimensionless (SystemSpec.alpha_f, SystemSpec.eta).

examples:
  gfbjax optimize --speed 0.35                             stabilise the cycle at Omega_bar 0.35 (max|mu|)
  gfbjax optimize --speed 0.35 --objective W_cb --method pattern --max-evals 60
  gfbjax optimize --start 0.3 --end 0.6 --step 0.025       optimised continuation (paper Figs. 16-19)
  gfbjax optimize --speed 0.4 --x0 0.5 0.2 --nx 24 --nz 3 --N 12
"""


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(NAME, help="foil design (alpha_f, eta) for the limit cycle: at one speed or along "
                                         "the speed (paper Figs. 16-19)",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)
    g = p.add_argument_group("objective and optimiser")
    g.add_argument("--objective", choices=OBJECTIVES, default="max_mu",
                   help="max_mu: minimise the largest non-trivial |Floquet multiplier|; W_cb: maximise the gas-film "
                        "dissipation per cycle (default %(default)s)")
    g.add_argument("--method", choices=METHODS, default="gradient",
                   help="gradient: projected quasi-Newton with exact gradients; adam: optax Adam; pattern: the "
                        "paper's pattern search (default %(default)s)")
    g.add_argument("--x0", nargs=2, type=float, default=None, metavar=("ALPHA_F", "ETA"),
                   help=f"start foil, alpha_f in {limits.DESIGN_ALPHA_F.interval()} and eta in "
                        f"{limits.DESIGN_ETA.interval()} (default: the system's own alpha_f and eta)")
    g.add_argument("--max-evals", type=int, default=None, metavar="E",
                   help="most cycle evaluations per speed, >= 1 (default: none; the optimiser's own stopping rules)")
    s = p.add_argument_group("speed: one speed (--speed) or an optimised continuation (--start, --end, --step)")
    add_speed_option(s, "--speed", default=None, rpm_flag="--rpm",
                     help=f"optimise at this speed, Omega_bar in {limits.SPEED.interval()}")
    add_speed_option(s, "--start", default=None, help="first speed of the continuation, in Omega_bar")
    add_speed_option(s, "--end", default=None,
                     help=f"last speed of the continuation in Omega_bar, above --start, at most {limits.SPEED.hi:g}")
    add_speed_option(s, "--step", default=None, metavar="D_OMEGA",
                     help=f"speed step of the continuation in Omega_bar, in {limits.SPEED_STEP.interval()} "
                          f"(default {DEFAULT_STEP:g})")
    n = p.add_argument_group("numerics (the collocation mesh of every cycle, as in gfbjax cycles)")
    n.add_argument("--m", type=int, default=4, metavar="M",
                   help=f"Gauss points per mesh interval, in {limits.COLLOCATION_M.interval()} (default 4)")
    n.add_argument("--N", type=int, default=16, metavar="N",
                   help=f"mesh intervals over the period, in {limits.MESH_N.interval()} (default 16)")
    o = p.add_argument_group("output")
    o.add_argument("--no-figures", action="store_true", help="no PNG figure")
    o.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=run)
    return p


def check_options(args: argparse.Namespace, spec: Any) -> tuple[float, float]:
    """Check every option before any computation (ParameterError naming the option); returns the start foil."""
    check_range("--m", args.m, limits.COLLOCATION_M)
    check_range("--N", args.N, limits.MESH_N)
    if args.max_evals is not None:
        check_option("--max-evals", args.max_evals, 1, 10**6, what="cycle evaluations per speed", integer=True)
    continuation = args.start is not None or args.end is not None or args.step is not None
    if args.speed is not None:
        if continuation:
            raise ParameterError("--speed: give either --speed (one speed) or --start/--end/--step "
                                 "(continuation), not both")
        check_range("--speed", args.speed, limits.SPEED)
    else:
        if not continuation:
            raise ParameterError("--speed: give --speed OMEGA_BAR (one speed) or both --start and --end "
                                 "(optimised continuation)")
        for opt, value in (("--start", args.start), ("--end", args.end)):
            if value is None:
                raise ParameterError(f"{opt}: the optimised continuation needs both --start and --end")
        check_range("--start", args.start, limits.SPEED)
        check_range("--end", args.end, limits.SPEED.with_bounds(lo=args.start, what="Omega_bar, above --start"))
        check_range("--step", DEFAULT_STEP if args.step is None else args.step, limits.SPEED_STEP)
    x0 = (spec.alpha_f, spec.eta) if args.x0 is None else tuple(args.x0)
    whose = "" if args.x0 is not None else "the system's own "
    for k, rng in enumerate((limits.DESIGN_ALPHA_F, limits.DESIGN_ETA)):
        check_range("--x0", x0[k], rng.with_bounds(what=f"{whose}{rng.name}, {rng.what}"))
    return float(x0[0]), float(x0[1])


def run(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    spec = spec_from_args(args)
    resolve_speeds(args, spec, ("--speed", "--rpm"), "--start", "--end")
    resolve_speeds(args, spec, "--step", rng=limits.SPEED_STEP)
    x0 = check_options(args, spec)
    out = output_dir(args)
    params = traced_params(spec)
    options = {} if args.max_evals is None else {"max_evals": args.max_evals}
    where = (f"Omega_bar {args.speed:g}" if args.speed is not None else
             f"Omega_bar {args.start:g} -> {args.end:g} step {args.step or DEFAULT_STEP:g}")
    print(f"gfbjax optimize: system '{args.system}', grid Nx={spec.Nx} Nz={spec.Nz}, collocation N={args.N} "
          f"m={args.m}, {where}, objective {args.objective}, method {args.method}, start alpha_f={x0[0]:g} "
          f"eta={x0[1]:g}", flush=True)
    meta = {
        "command": NAME, "system": {"name": args.system, "spec": spec.to_dict(), "t_star_s": spec.t_star},
        "objective": args.objective, "method": args.method, "x0": {"alpha_f": x0[0], "eta": x0[1]},
        "settings": {"m": args.m, "N": args.N, "max_evals": args.max_evals},
    }
    try:
        if args.speed is not None:
            return _one_speed(args, spec, params, x0, options, out, meta, t0)
        return _continuation(args, spec, params, x0, options, out, meta, t0)
    except NoSolutionError as exc:  # no static equilibrium at the (first) speed, or no cycle at all
        print(f"gfbjax optimize: {exc}", flush=True)
        return 1


def _finish(out: Any, name: str, data: dict[str, Any], figure: Any, t0: float) -> None:
    """Write the figure (unless None) and the JSON summary; print where."""
    import gfbjax

    files = [name + ".json"]
    if figure is not None:
        import matplotlib.pyplot as plt

        figure.savefig(out / f"{name}.png", dpi=130, bbox_inches="tight")
        plt.close(figure)
        files.append(name + ".png")
    data = {**data, "gfbjax_version": gfbjax.__version__, "files": files,
            "timings_s": {"total": time.perf_counter() - t0}}
    write_summary(out, f"{name}.json", data)


def _one_speed(args, spec, params, x0, options, out, meta, t0) -> int:
    import numpy as np

    from ...design.evaluate import FoilDesign
    from ...design.schedule import optimize_at_speed

    design = FoilDesign(params, args.speed, m=args.m, N=args.N)
    opt = optimize_at_speed(design, args.objective, args.method, x0, progress=not args.quiet, **options)
    ev = opt.evaluation
    hist = np.asarray(opt.history, float).reshape(-1, 4)
    mods = np.sort(np.abs(np.asarray(ev.multipliers)))[::-1]
    print("\n".join([
        f"  optimum           alpha_f = {opt.alpha_f:.6g}, eta = {opt.eta:.6g}",
        f"  objective         {args.objective} = {opt.value:.6g}",
        f"  cycle             W_cb = {ev.W_cb:.6g} p0 R L c, max|mu| = {ev.max_mu:.6f} "
        f"({'stable' if ev.stable else 'unstable'})",
        f"  cost              {opt.n_solves} cycle solves, {opt.n_gradients} gradients, {opt.seconds:.1f} s "
        f"(stopped: {opt.reason})",
        f"  accuracy          multiplier error {ev.multiplier_error:.1e} (frozen-coefficient model and mode defects)"
        + ("" if ev.resolved else f"; FLAGGED: max|mu| is not resolved at N = {args.N} (at low speed the film's "
           "fast modes or the rotor mode): raise --N"),
    ]), flush=True)
    data = {
        **meta, "Omega_bar": args.speed, "rpm": spec.rpm(args.speed),
        "alpha_f": opt.alpha_f, "eta": opt.eta, "objective_value": opt.value, "W_cb": ev.W_cb,
        "W_cb_J": ev.W_cb * work_unit_J(spec), "running_frequency_Hz": speed_si(spec, args.speed)["running_frequency_Hz"],
        "max_mu": ev.max_mu, "stable": ev.stable, "energy": ev.energy._asdict(),
        "multiplier_error": ev.multiplier_error, "stiff_modulus": ev.stiff_modulus, "max_mu_resolved": ev.resolved,
        "multiplier_moduli": mods[:8], "n_solves": opt.n_solves, "n_gradients": opt.n_gradients,
        "seconds": opt.seconds, "reason": opt.reason,
        "history": {"columns": ["alpha_f", "eta", args.objective, "seconds"], "rows": hist},
    }
    fig = None if args.no_figures else _plot_optimum(hist, x0, opt, args, spec)
    _finish(out, "optimum", data, fig, t0)
    return 0


def _continuation(args, spec, params, x0, options, out, meta, t0) -> int:
    import numpy as np

    from ...cont import Outcome
    from ...design.schedule import optimized_continuation

    step = DEFAULT_STEP if args.step is None else args.step
    sched = optimized_continuation(params, args.start, args.end, step, objective=args.objective,
                                   method=args.method, x0=x0, m=args.m, N=args.N, progress=not args.quiet,
                                   **options)
    lines = [f"    {'Omega_bar':>9} {'alpha_f':>10} {'eta':>10} {'W_cb':>11} {'max|mu|':>9}  stable"]
    for row in zip(sched.omega, sched.alpha_f, sched.eta, sched.W_cb, sched.max_mu, sched.stable,
                   sched.max_mu_resolved):
        w, a, e, wcb, mu, st, ok = row
        flag = "" if ok else f"  FLAGGED: max|mu| not resolved at N = {args.N} (raise --N)"
        lines.append(f"    {w:>9.4f} {a:>10.4g} {e:>10.4g} {wcb:>11.4g} {mu:>9.5f}  {'yes' if st else 'no '}{flag}")
    free = sched.bifurcation_free_to
    print("\n".join([
        "  schedule", *lines,
        "  stable up to      " + (f"Omega_bar = {free:.4f} ({spec.rpm(free):.0f} rpm)" if free is not None
                                   else "none (no stable optimised cycle)"),
        f"  ended             {sched.outcome}: {sched.message}",
        f"  cost              {sched.n_solves} cycle solves, {sched.n_gradients} gradients, {sched.seconds:.1f} s",
    ]), flush=True)
    fig = None
    if not args.no_figures and sched.omega:
        from ...plot.branch import plot_schedule

        fig = plot_schedule([(f"{args.objective}, {args.method}", sched)], spec=spec,
                            title=f"Optimised foil along the speed, system '{args.system}' (Nx={spec.Nx}, "
                                  f"Nz={spec.Nz}, N={args.N}, m={args.m}; x: unstable)")
    data = {**meta, "range": {"start": args.start, "end": args.end, "step": step}, **sched.to_dict()}
    data["SI"] = {"rpm": [spec.rpm(float(w)) for w in sched.omega],
                  "W_cb_J": [float(v) * work_unit_J(spec) for v in sched.W_cb],
                  "journal_max_um": [(np.asarray(a) * spec.c * 1e6).tolist() for a in sched.journal_max],
                  "journal_min_um": [(np.asarray(a) * spec.c * 1e6).tolist() for a in sched.journal_min],
                  "bifurcation_free_to_rpm": None if free is None else spec.rpm(free)}
    _finish(out, "schedule", data, fig, t0)
    return 0 if sched.outcome is Outcome.REACHED_END else 1


def _plot_optimum(hist: Any, x0: tuple[float, float], opt: Any, args: argparse.Namespace, spec: Any):
    """Objective value per evaluation (with the best so far) and the path of the evaluations in the
    (alpha_f, eta) plane on log axes, inside the bounds."""
    import matplotlib.pyplot as plt
    import numpy as np

    from ...design.evaluate import FOIL_BOUNDS

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    k = np.arange(1, len(hist) + 1)
    v = hist[:, 2]
    best = np.maximum.accumulate(v) if args.objective == "W_cb" else np.minimum.accumulate(v)
    ax1.plot(k, v, "o", color="tab:blue", ms=4, label="evaluation")
    ax1.step(k, best, where="post", color="tab:red", lw=1.4, label="best so far")
    if args.objective == "max_mu":
        ax1.axhline(1.0, color="k", ls="--", lw=0.9, label=r"$|\mu| = 1$")
    ax1.xaxis.get_major_locator().set_params(integer=True)
    ax1.set_xlabel("cycle evaluation")
    ax1.set_ylabel(r"max $|\mu|$" if args.objective == "max_mu" else r"$W_{cb}$ [$p_0 R L c$]")
    ax1.set_title(f"objective {args.objective} ({args.method})", fontsize=10)
    (alo, ahi), (elo, ehi) = FOIL_BOUNDS["alpha_f"], FOIL_BOUNDS["eta"]
    ax2.plot([alo, ahi, ahi, alo, alo], [elo, elo, ehi, ehi, elo], ":", color="0.5", lw=1, label="bounds")
    ax2.plot(hist[:, 0], hist[:, 1], "-o", color="tab:blue", ms=3, lw=0.8, alpha=0.8, label="evaluations")
    ax2.plot(*x0, "s", color="k", ms=8, label="start")
    ax2.plot(opt.alpha_f, opt.eta, "*", color="tab:red", ms=14, mec="k", label="optimum")
    ax2.set_xscale("log")
    ax2.set_yscale("log")
    ax2.set_xlabel(r"foil compliance $\alpha_f$")
    ax2.set_ylabel(r"foil loss factor $\eta$")
    ax2.set_title(r"path in ($\alpha_f$, $\eta$)", fontsize=10)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="best")
    fig.suptitle(f"Foil optimisation at Omega_bar = {args.speed:g}, system '{args.system}' (Nx={spec.Nx}, "
                 f"Nz={spec.Nz}, N={args.N}, m={args.m})")
    fig.tight_layout()
    return fig
