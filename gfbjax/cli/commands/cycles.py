"""``gfbjax cycles``: branch of unbalance-response limit cycles over a speed range by collocation and pseudo-arclength
continuation, with Floquet stability and the fold (LPC), period-doubling (PD) and Neimark-Sacker (NS) points
(paper Sect. 2.3, 3.2, Appendix A1)."""

from __future__ import annotations

import argparse
import math
import time
from ...limits import NoSolutionError
from typing import Any

from ... import limits
from ...params import ParameterError
from ._checkpoints import add_checkpoint_options, interrupted_status, prepare_run, restored_rows
from ._contact import accuracy_line, accuracy_summary, add_contact_options, contact_line, contact_summary
from ._common import (add_speed_option, add_step_options, add_system_options, branch_row_um, check_chord_tol,
                      check_continuation_options, check_option, check_range, speed_si, write_summary)

NAME = "cycles"

DESCRIPTION = """\
Continuation of the synchronous (1X) limit cycles of the unbalanced rotor in the speed Omega_bar, from the linear
forced response at --start towards --end: orthogonal collocation (--N intervals of degree --m), pseudo-arclength
steps, Floquet multipliers at every point, and the fold (LPC), period-doubling (PD) and Neimark-Sacker (NS)
bifurcations, located by regula falsi unless --no-locate.  A progress bar advances with the speed.

Writes to --out: branch.npz + branch.json (the branch with the collocation states of every point, for
'gfbjax energy --branch' and restarts; gfbjax.cont.Branch.load; plain numpy + json; the JSON
records the system spec and its conventions, the grid, the component names, units and the rpm conversion),
cycles.json (summary: special points with speed, rpm, multipliers' moduli, NS angle; why the branch ended;
counts; timings), checkpoint/ (every point as it is accepted, for --resume), cycles_bifurcation.png (max/min of the journal y_j and x_j against speed, stable solid,
unstable dashed, special points marked) and cycles_multipliers.png (Floquet multipliers and unit circle).
Exit status: 0 when the branch reached --end, 1 when it ended early (everything is still written), 2 for
invalid input, 130 when interrupted (Ctrl-C or SIGTERM; continue with --resume).
"""

EPILOG = """\
units: speeds are dimensionless, Omega_bar = Omega t* (the bearing number); displacements over the clearance c.
The arclength metric contains the period T = 2 pi / Omega_bar, so steps --ds are large; --dlam-max caps the speed
change per step.  Points are placed where the branch bends: straight lines between them stay within --chord-tol of
the plotted curves (each scaled by its range); --chord-tol inf gives steps set by --ds-max and --dlam-max alone.

examples:
  gfbjax cycles                                   reference system, Omega_bar 0.05 -> 1.0
  gfbjax cycles --nx 24 --nz 3 --N 16              coarser grid, about 2 minutes
  gfbjax cycles --system ks3 --start 0.2 --end 0.8 --dlam-max 0.01
"""

# option -> CycleSettings field
_FIELDS = {"m": "--m", "N": "--N", "ds": "--ds", "ds_max": "--ds-max", "dlam_max": "--dlam-max",
           "chord_tol": "--chord-tol", "max_points": "--max-points", "ds_min": "--ds", "lam_min": "--start",
           "lam_max": "--end"}


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(NAME, help="limit cycles vs speed: continuation, Floquet stability, LPC/PD/NS points",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)
    r = p.add_argument_group("speed range")
    add_speed_option(r, "--start", default=0.05, help="start speed in Omega_bar (default 0.05)")
    add_speed_option(r, "--end", default=1.0,
                     help="end speed in Omega_bar (default 1.0); below --start the branch runs down in speed")
    n = p.add_argument_group("numerics")
    add_step_options(n)
    n.add_argument("--collocation", choices=("gauss", "radau"), default="gauss",
                   help="collocation points: gauss (default; order 2m, as AUTO and the paper) or radau "
                        "(L-stable: the film's fast modes get multipliers near 0 instead of spurious ones near the "
                        "unit circle, but modes oscillating faster than the mesh resolves are damped away)")
    n.add_argument("--no-locate", action="store_true",
                   help="do not locate the bifurcations (report the step where they were detected)")
    add_contact_options(p)
    o = p.add_argument_group("output")
    o.add_argument("--no-figures", action="store_true", help="no PNG figures")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    add_checkpoint_options(p)
    p.set_defaults(func=run)
    return p


def _settings(args: argparse.Namespace):
    from ...analyses.cycles import default_cycle_settings

    check_continuation_options(args)
    check_range("--m", args.m, limits.COLLOCATION_M)
    check_range("--N", args.N, limits.MESH_N)
    check_option("--dlam-max", args.dlam_max, 0.0, None, lo_open=True, what="speed change per step")
    check_chord_tol(args.chord_tol)
    try:
        return default_cycle_settings(m=args.m, N=args.N, ds=args.ds, ds_min=min(1e-4, args.ds),
                                      ds_max=args.ds_max, dlam_max=args.dlam_max, chord_tol=args.chord_tol,
                                      max_points=args.max_points,
                                      locate=not args.no_locate, save_states=True,
                                      collocation=args.collocation)
    except ValueError as exc:
        msg = str(exc)
        field = msg.split()[0] if msg else ""
        opt = _FIELDS.get(field, "numerics")
        raise ParameterError(f"{opt}: {msg}") from None


def reached_end(branch: Any, start: float, end: float) -> bool:
    """Whether the branch got to (or past) ``end``."""
    if len(branch.lam) == 0:
        return False
    last = float(branch.lam[-1])
    tol = 1e-9 * max(1.0, abs(end))
    return last >= end - tol if end > start else last <= end + tol


def special_summary(branch: Any, spec: Any) -> list[dict[str, Any]]:
    """The special points of a cycle branch for the JSON summary and the table."""
    import numpy as np

    from ...cont import nontrivial

    out = []
    for s in branch.special:
        mu = np.asarray(s.spectrum, complex)
        crit = nontrivial(mu, 1) if mu.size else mu
        crit = crit[np.argsort(-np.abs(crit))] if crit.size else crit
        lam = float(s.lam)
        d: dict[str, Any] = {
            "type": s.type, "Omega_bar": lam, "rpm": spec.rpm(lam), "period": s.period,
            "located": bool(s.located), "localisation": s.localisation,
            "residual": None if math.isnan(s.residual) else s.residual, "index": s.index,
            # the estimated error of Omega_bar: the zero's move on other meshes (SpecialPoint.lam_error)
            "Omega_bar_error": None if math.isnan(s.lam_error) else s.lam_error,
            "multiplier_moduli": [float(v) for v in np.abs(crit[:4])],
            "critical_multipliers": [[float(z.real), float(z.imag)] for z in crit[:2]],
        }
        if s.type == "NS" and s.angle is not None:
            a = float(s.angle)
            d["ns_angle_rad"] = a
            d["ns_angle_deg"] = math.degrees(a)
            # the second frequency of the torus, as a multiple of the running frequency (modulo 1)
            d["ns_frequency_ratio"] = a / (2 * math.pi)
        si = speed_si(spec, lam)
        if "ns_frequency_ratio" in d:
            si["ns_frequency_Hz"] = d["ns_frequency_ratio"] * si["running_frequency_Hz"]
        d["SI"] = {**si, **branch_row_um(branch, s.index, spec)}
        # an unlocated point's place and data are those of a bracket or of the next point, not of a zero
        d["flags"] = ([] if s.located else [s.localisation]) + _row_flags(branch, s.index)
        out.append(d)
    return out


def _row_flags(branch: Any, i: int) -> list[str]:
    """Why the branch row of a special point is flagged: "film contact" (the model does not apply there: the point
    is not physical), "trivial error", "mesh error" (not resolved: the location and the label are unreliable)."""
    if not 0 <= i < len(branch):
        return []
    out = []
    info = branch.monitor_info or {}
    if branch.monitor is not None and "minimum" in info and float(branch.monitor[i]) <= float(info["minimum"]):
        out.append("film contact")
    if branch.accuracy_tol is not None and float(branch.trivial_error[i]) > branch.accuracy_tol:
        out.append("trivial error")
    if branch.mesh_error is not None and branch.mesh_tol is not None and float(branch.mesh_error[i]) > branch.mesh_tol:
        out.append("mesh error")
    if (branch.stiff_modulus is not None and branch.stiff_tol is not None
            and float(branch.stiff_modulus[i]) > branch.stiff_tol):
        out.append("spurious multipliers")
    if (branch.multiplier_error is not None and branch.multiplier_tol is not None
            and float(branch.multiplier_error[i]) > branch.multiplier_tol):
        out.append("multipliers unresolved")
    return out


def format_table(rows: list[dict[str, Any]]) -> str:
    if not rows:
        return "  special points    none"
    lines = ["  special points", f"    {'type':<5} {'Omega_bar':>10} {'+-':>8} {'rpm':>9}  "
             f"{'|mu| (largest non-trivial)':<30} {'NS angle':>12}  {'placed':<13}"]
    for d in rows:
        mods = ", ".join(f"{v:.4f}" for v in d["multiplier_moduli"][:3])
        ang = f"{d['ns_angle_rad']:.4f} rad" if "ns_angle_rad" in d else ""
        flags = f"  FLAGGED: {', '.join(d['flags'])}" if d.get("flags") else ""
        err = d.get("Omega_bar_error")
        lines.append(f"    {d['type']:<5} {d['Omega_bar']:>10.5f} {'?' if err is None else f'{err:.1e}':>8} "
                     f"{d['rpm']:>9.0f}  {mods:<30} {ang:>12}  {d['localisation']:<13}{flags}")
    return "\n".join(lines)


class _SpeedBar:
    """tqdm progress bar advancing with Omega_bar (callback of the continuation)."""

    def __init__(self, start: float, end: float, enabled: bool, restored: int = 0) -> None:
        self.start, self.end = start, end
        self.bar = None
        # restored > 0 (a resumed run): the first call is the checkpoint's last row, computed by an earlier run
        self.restored = restored
        self.computed = 0  # rows computed by this run
        self.done = 0.0
        if enabled:
            try:
                from tqdm.auto import tqdm

                # Until the first point the time goes into compiling the solver's kernels (or loading them from
                # the compilation cache) and the start's correction: an ETA from it would be meaningless.
                self.bar = tqdm(total=round(abs(end - start), 6), desc="cycles (compiling, first point)",
                                bar_format="{l_bar}{bar}| [{elapsed}<{remaining}{postfix}]")
            except ImportError:  # pragma: no cover
                self.bar = None
        self.first = True
        self.t_first: float | None = None  # perf_counter() at the first point (compilation and start included)

    def __call__(self, index: int, rec: Any) -> None:
        if index >= self.restored:
            self.computed += 1
            if self.t_first is None:
                self.t_first = time.perf_counter()
        if self.bar is None:
            return None
        if self.first:  # rates and ETAs count from the first point, after the compilation
            self.first = False
            self.bar.reset(total=self.bar.total)
            self.bar.set_description("cycles", refresh=False)
        lam = float(rec.lam)
        frac = min(max((lam - self.start) / (self.end - self.start), 0.0), 1.0) * abs(self.end - self.start)
        if frac > self.done:  # set the position (not increments) so that rounding never overshoots the total
            self.done = min(round(frac, 6), self.bar.total)
            self.bar.n = self.done
            self.bar.refresh()
        self.bar.set_postfix_str(f"Omega_bar={lam:.4f}, point {index + 1}, {'stable' if rec.stable else 'unstable'}",
                                 refresh=False)
        return None

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _time_split(t_cont: float, t_start: float, bar: _SpeedBar) -> str:
    """The continuation's time split at the first point this run computed, which carries the compilation (and
    the start's correction): a per-point figure over all points would charge the compilation to every point, and
    one over the rows of a resumed run would count rows an earlier run computed."""
    points, t_first = bar.computed, bar.t_first
    resumed = f"resumed after {bar.restored} rows; " if bar.restored else ""
    if not points or t_first is None:
        return f" ({resumed}no new point)" if bar.restored else ""
    if points < 2:
        return f" ({resumed}{t_cont / points:.2f} s per point)"
    first = t_first - t_start
    return (f" ({resumed}first point {first:.1f} s, compilation included; then {(t_cont - first) / (points - 1):.2f} s "
            "per point)")


def run(args: argparse.Namespace) -> int:
    import numpy as np

    import gfbjax

    from ...analyses.cycles import continue_gfb_cycles, rotor_components

    t0 = time.perf_counter()
    args, spec, settings, out, params, contact, ck = prepare_run(args, NAME, _settings)
    print(f"gfbjax cycles: system '{args.system}', grid Nx={spec.Nx} Nz={spec.Nz}, collocation N={settings.N} "
          f"m={settings.m}, Omega_bar {args.start:g} -> {args.end:g}"
          + (f", resuming {ck}" if args.resume is not None else ""), flush=True)
    bar = _SpeedBar(args.start, args.end, not args.quiet, restored_rows(ck))
    t1 = time.perf_counter()
    try:
        branch = continue_gfb_cycles(params, args.start, args.end, settings, callback=bar, spec=spec,
                                     checkpoint=ck, **contact)
    except NoSolutionError as exc:  # no static equilibrium at the start speed
        bar.close()
        print(f"gfbjax cycles: {exc}", flush=True)
        return 1
    bar.close()
    t_cont = time.perf_counter() - t1
    branch.save(out / "branch")
    ok = reached_end(branch, args.start, args.end)
    rows = special_summary(branch, spec)
    c_um = spec.c * 1e6
    n_stable = int(np.sum(branch.stable))
    lines = [
        f"  branch            {len(branch)} points ({n_stable} stable, {len(branch) - n_stable} unstable), "
        f"Omega_bar {float(branch.lam[0]) if len(branch) else math.nan:.4f} -> "
        f"{float(branch.lam[-1]) if len(branch) else math.nan:.4f}",
        f"  ended             {branch.outcome}: {branch.message}" + ("" if ok else "  (before the end of the range)"),
        f"  time              continuation {t_cont:.1f} s" + _time_split(t_cont, t1, bar),
        format_table(rows),
    ]
    if len(branch) and branch.monitor is not None:
        lines.insert(1, contact_line(branch, spec))
    acc = accuracy_summary(branch)
    if len(branch):
        lines.insert(1, accuracy_line(acc))
    print("\n".join(lines), flush=True)

    figures: list[str] = []
    t2 = time.perf_counter()
    if not args.no_figures and len(branch):
        import matplotlib.pyplot as plt

        from ...plot.branch import plot_bifurcation, plot_multipliers

        fig = plot_bifurcation(branch, c_um=c_um, spec=spec, title=f"Limit cycles, system '{args.system}' "
                                                        f"(Nx={spec.Nx}, Nz={spec.Nz}, N={settings.N}, m={settings.m})",
                               path=out / "cycles_bifurcation.png")
        plt.close(fig)
        figures.append("cycles_bifurcation.png")
        fig = plot_multipliers(branch, title=f"Floquet multipliers, system '{args.system}'",
                               path=out / "cycles_multipliers.png")
        plt.close(fig)
        figures.append("cycles_multipliers.png")
    t_fig = time.perf_counter() - t2

    comps = rotor_components(params, True)
    data = {
        "command": NAME, "gfbjax_version": gfbjax.__version__,
        "system": {"name": args.system, "spec": spec.to_dict(), "t_star_s": spec.t_star, "c_um": c_um},
        "range": {"start": args.start, "end": args.end, "reached_end": ok,
                  "start_rpm": spec.rpm(args.start), "end_rpm": spec.rpm(args.end)},
        "settings": {"m": settings.m, "N": settings.N, "ds": settings.ds, "ds_max": settings.ds_max,
                     "dlam_max": settings.dlam_max, "chord_tol": settings.chord_tol, "max_points": settings.max_points,
                     "locate": settings.locate,
                     "collocation": settings.collocation},
        "outcome": str(branch.outcome), "message": branch.message,
        "counts": {"points": len(branch), "stable": n_stable, "unstable": len(branch) - n_stable,
                   "special": len(rows), **{k: sum(1 for d in rows if d["type"] == k) for k in ("LPC", "PD", "NS", "BPC")}},
        "film": contact_summary(branch, spec),
        "accuracy": acc,
        "lam_first": float(branch.lam[0]) if len(branch) else None,
        "lam_last": float(branch.lam[-1]) if len(branch) else None,
        "components": {"names": ["x_j", "y_j", "x_d", "y_d"][:len(comps)], "state_indices": comps},
        "special": rows,
        "files": ["branch.npz", "branch.json", "cycles.json"] + figures,
        "timings_s": {"setup": t1 - t0, "continuation": t_cont, "figures": t_fig,
                      "first_point": None if bar.t_first is None else bar.t_first - t0,
                      "total": time.perf_counter() - t0},
    }
    write_summary(out, "cycles.json", data)
    return interrupted_status(branch, ok, out, ck, NAME)
