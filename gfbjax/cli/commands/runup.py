"""``gfbjax runup``: run-up (or coast-down) transient at constant angular acceleration (paper Eq. 15b, Fig. 7a-c):
time history of the journal against speed, STFT spectrogram in multiples of the running frequency, and the speeds
where sub-synchronous components appear."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from typing import Any

from ... import limits
from ...params import ParameterError, SystemSpec
from ._common import (add_speed_option, add_system_options, check_option, check_range, output_dir, resolve_speeds,
                      spec_from_args, traced_params, write_json)

NAME = "runup"

DESCRIPTION = """\
Run-up (end > start) or coast-down (end < start) of the unbalanced rotor at constant angular acceleration
(paper Eq. 15b), integrated with diffrax (Kvaerno5, sparse Jacobian, dense LU) from the static equilibrium at the
start speed, after --settle-revs revolutions at the start speed.  A progress bar advances per chunk; a rub (the
film thickness reaching --h-rub) ends the run and keeps what was computed.

Writes to --out: runup.npz (time history: tau, speed, rotor states, h_min; gfbjax.analyses.transient.TransientResult.load),
runup.json (summary, sub-synchronous speed ranges, solver statistics), runup_response.png (journal vertical and
horizontal displacement against speed, paper Fig. 7a/b) and runup_stft.png (STFT against speed, Fig. 7c).
Exit status: 0 completed, 1 rub or solver failure, 2 invalid input.
"""

EPILOG = """\
units: speeds are dimensionless, Omega_bar = Omega t* (the bearing number); accel is per tau^2 (tau = t/t*);
displacements over the clearance c.

examples:
  gfbjax runup                                    reference system, Omega_bar 0.05 -> 1.0 in 400 revolutions
  gfbjax runup --start 0.2 --end 0.6 --revs 150 --nx 24 --nz 3
  gfbjax runup --system ks3 --start 1.0 --end 0.1 --revs 300      coast-down
"""


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(NAME, help="run-up/coast-down transient, STFT and sub-synchronous onset (Fig. 7)",
                              description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)
    r = p.add_argument_group("run-up")
    add_speed_option(r, "--start", default=0.05, help="start speed in Omega_bar (default 0.05)")
    add_speed_option(r, "--end", default=1.0, help="end speed in Omega_bar (default 1.0)")
    a = r.add_mutually_exclusive_group()
    a.add_argument("--revs", type=float, default=None, metavar="N",
                   help="revolutions from start to end speed, sets the acceleration (default 400; in "
                        f"{limits.REVOLUTIONS.interval()})")
    a.add_argument("--accel", type=float, default=None, metavar="A_BAR",
                   help=f"angular acceleration per tau^2, |A_BAR| in {limits.ACCEL.interval()}: positive for a "
                        f"run-up, negative for a coast-down; at most {limits.REVOLUTIONS.hi:g} revolutions")
    r.add_argument("--settle-revs", type=float, default=20.0, metavar="N",
                   help="revolutions at the start speed before the run-up, so that the start transient has "
                        "decayed (default 20; 0 = none)")
    s = p.add_argument_group("solver")
    s.add_argument("--solver", default="kvaerno5", choices=["kvaerno5", "kvaerno4", "kvaerno3"])
    s.add_argument("--rtol", type=float, default=1e-5, help="relative tolerance (default 1e-5)")
    s.add_argument("--atol", type=float, default=1e-7, help="absolute tolerance (default 1e-7)")
    s.add_argument("--samples-per-rev", type=int, default=32, help="saved samples per revolution at the top speed")
    s.add_argument("--chunk-revs", type=float, default=10.0, help="revolutions per chunk (progress bar step)")
    s.add_argument("--h-rub", type=float, default=0.01, help="film thickness h/c that counts as rub (default 0.01)")
    o = p.add_argument_group("analysis and output")
    o.add_argument("--segment-revs", type=float, default=12.0,
                   help="STFT segment length in revolutions at the top speed (default 12)")
    o.add_argument("--rel", type=float, default=0.1,
                   help="a sub-synchronous peak counts above this fraction of the 1X amplitude (default 0.1)")
    o.add_argument("--floor", type=float, default=1e-3,
                   help="... and above this absolute amplitude over c (default 1e-3)")
    o.add_argument("--cycles", default=None, metavar="BRANCH",
                   help="overlay the max/min of the limit cycles of a branch file written by 'gfbjax cycles' "
                        "(e.g. results/cycles/branch.npz) on the run-up figure, as in the paper's Fig. 7a/b; the "
                        "branch must be of the same system (its grid --nx/--nz may differ)")
    o.add_argument("--no-figures", action="store_true", help="no PNG figures")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    import gfbjax

    from ...analyses.signals import runup_stft, subsynchronous
    from ...analyses.transient import default_initial_state, run_up, simulate

    t_start = time.perf_counter()
    spec = spec_from_args(args)
    resolve_speeds(args, spec, "--start", "--end")
    params = traced_params(spec)
    settings, settle_revs, revs = _check_run(args, params)
    overlay = _cycle_overlay(args.cycles, spec, args.system)  # before the long integration: a bad file fails fast
    out = output_dir(args)
    progress = not args.quiet

    s0, note = default_initial_state(params, args.start)
    print(f"gfbjax runup: system '{args.system}', grid Nx={spec.Nx} Nz={spec.Nz}, Omega_bar {args.start:g} -> "
          f"{args.end:g}; {note}", flush=True)
    if settle_revs > 0:
        settle = simulate(params, args.start, revolutions=settle_revs, s0=s0, settings=settings,
                          progress=progress)
        if settle.outcome != "completed":
            print(f"  settling at the start speed ended: {settle.message}", flush=True)
            settle.save(out / "runup.npz")
            return 1
        s0 = settle.final_state
    res = run_up(params, args.start, args.end, accel=args.accel, revolutions=revs, s0=s0, settings=settings,
                 progress=progress)
    res.save(out / "runup.npz")

    c_um = spec.c * 1e6
    st = res.stats
    lines = [
        f"  outcome           {res.outcome}: {res.message}",
        f"  acceleration      a_bar = {res.accel:.4g} per tau^2 ({res.revolutions:.1f} revolutions, "
        f"tau = {res.tau[-1]:.5g}, {res.tau[-1] * spec.t_star:.4g} s)",
        f"  solver            {settings.solver}, rtol {settings.rtol:g}, atol {settings.atol:g}: {st['steps']} steps "
        f"({st['rejected']} rejected), wall {st['wall_s']:.1f} s, CPU {st['cpu_s']:.1f} s, "
        f"{st['steps_per_s']:.0f} steps/s, {st['revs_per_s']:.2f} rev/s",
        f"  film              min h = {res.h_min.min():.4f} c ({res.h_min.min() * c_um:.2f} um)",
    ]
    ranges: dict[str, list] = {}
    spectros = {}
    if res.tau.size > 64:
        for key, sig in (("y_j", res.y_j), ("x_j", res.x_j)):
            sg = runup_stft(res.tau, sig, res.speed, segment_revs=args.segment_revs)
            spectros[key] = sg
            ranges[key] = subsynchronous(sg, rel=args.rel, floor=args.floor)
        for key, rs in ranges.items():
            if not rs:
                lines.append(f"  sub-synchronous   {key}: none above {args.rel:g} x 1X and {args.floor:g} c")
            for r in rs:
                lines.append(f"  sub-synchronous   {key}: Omega_bar {r.speed_start:.4f} - {r.speed_end:.4f}, "
                             f"strongest at {r.order:.3f} X (omega = {r.omega:.4f} per tau, "
                             f"{r.omega / spec.t_star / (2 * math.pi):.1f} Hz), {r.amplitude:.3g} c = "
                             f"{r.rel_amplitude:.2f} x 1X")
    print("\n".join(lines), flush=True)

    figures = []
    if not args.no_figures:
        import matplotlib.pyplot as plt

        from ...plot.transient import plot_runup, plot_spectrogram

        fig = plot_runup(res, overlay, c_um=c_um, spec=spec,
                         title=f"Run-up, system '{args.system}' (paper Fig. 7a/b)", path=out / "runup_response.png")
        plt.close(fig)
        figures.append("runup_response.png")
        if "y_j" in spectros:
            fig = plot_spectrogram(spectros["y_j"], subsync=ranges["y_j"], spec=spec,
                                   title=f"STFT of y_j, system '{args.system}' (paper Fig. 7c)",
                                   path=out / "runup_stft.png")
            plt.close(fig)
            figures.append("runup_stft.png")

    data = {
        "command": NAME, "gfbjax_version": gfbjax.__version__,
        "system": {"name": args.system, "spec": spec.to_dict(), "t_star_s": spec.t_star},
        "run": res.summary(),
        "subsynchronous": {k: [{**vars(r), "SI": {
            "rpm_start": spec.rpm(r.speed_start), "rpm_end": spec.rpm(r.speed_end),
            "frequency_Hz": r.omega / spec.t_star / (2 * math.pi), "amplitude_um": r.amplitude * spec.c * 1e6}}
            for r in rs] for k, rs in ranges.items()},
        "range": {"start": args.start, "end": args.end, "start_rpm": spec.rpm(args.start),
                  "end_rpm": spec.rpm(args.end)},
        "figures": figures, "total_s": time.perf_counter() - t_start,
    }
    write_json(out / "runup.json", data)
    print(f"  wrote             {out}/: runup.npz, runup.json" + "".join(f", {f}" for f in figures)
          + f"  ({data['total_s']:.1f} s)", flush=True)
    return 0 if res.outcome == "completed" else 1


def _check_run(args: argparse.Namespace, params: Any) -> tuple[Any, float, float | None]:
    """Check every option of the run before any computation (speeds, --revs or --accel with its sign and the
    revolutions it implies, --settle-revs, the solver settings, the memory of the saved samples).  Returns the
    settings, the settling revolutions (whole) and the run-up revolutions (None with --accel)."""
    from ...analyses.transient import TransientSettings, check_run_up, check_simulate

    for opt, value in (("--start", args.start), ("--end", args.end)):
        check_range(opt, value, limits.SPEED)
    if args.start == args.end:
        raise ParameterError(f"--end = {args.end:g} must differ from --start (a run-up or a coast-down)")
    if args.revs is not None:
        check_range("--revs", args.revs, limits.REVOLUTIONS)
    settle_revs = float(round(check_range("--settle-revs", args.settle_revs, limits.SETTLE_REVOLUTIONS)))
    check_option("--segment-revs", args.segment_revs, 0.0, 1e4, lo_open=True, what="revolutions per STFT segment")
    check_option("--rel", args.rel, 0.0, 1e3, lo_open=True, what="fraction of the 1X amplitude")
    check_option("--floor", args.floor, 0.0, 1e3, what="amplitude over c")
    revs = 400.0 if (args.revs is None and args.accel is None) else args.revs
    try:
        settings = TransientSettings(solver=args.solver, rtol=args.rtol, atol=args.atol,
                                     samples_per_rev=args.samples_per_rev, chunk_revs=args.chunk_revs,
                                     h_rub=args.h_rub)
        check_run_up(params, args.start, args.end, accel=args.accel, revolutions=revs, settings=settings)
    except (ParameterError, ValueError) as exc:  # name the option: "rtol = 0 ..." -> "--rtol = 0 ..."
        msg = str(exc)
        for name, option in _OPTIONS.items():
            if msg.startswith(f"{name} "):
                msg = option + msg[len(name):]
                break
        raise ParameterError(msg) from None
    if settle_revs > 0:
        check_simulate(params, args.start, revolutions=settle_revs, settings=settings)
    return settings, settle_revs, revs


def _cycle_overlay(path: str | None, spec: SystemSpec, system: str = "") -> dict | None:
    """Max/min of the journal displacement of a saved cycle branch, in the form ``plot_runup`` takes.

    The file is read with :meth:`gfbjax.cont.Branch.load`; a missing, corrupt or foreign file, a branch that is
    not of cycles or does not record x_j, y_j first, and a branch computed for another system are ParameterErrors
    naming ``--cycles`` (exit 2).  "Another system": any field of the branch's recorded SystemSpec other than
    the grid (Nx, Nz) differs from ``spec``, the unbalance compared as the eccentricity e_u that G and omega_r
    (or e_u) give, since the overlay compares the physics and a branch on a coarser grid is a fair reference.  A
    branch with only the dimensionless groups recorded (computed without ``spec``) is compared on those.  A
    branch that records no system (written by an older gfbjax) is accepted with a warning on stderr."""
    if path is None:
        return None
    from ...cont import Branch, BranchFileError

    try:
        b = Branch.load(path)
    except BranchFileError as exc:
        raise ParameterError(f"--cycles: {exc}") from None
    if b.kind != "cycles":
        raise ParameterError(f"--cycles {path}: branch kind is {b.kind!r}, expected 'cycles'")
    if b.xmax.shape[1] < 2 or (b.component_names is not None and list(b.component_names[:2]) != ["x_j", "y_j"]):
        raise ParameterError(f"--cycles {path}: the branch does not record the journal x_j, y_j first "
                             f"(components {b.component_names or b.components})")
    diffs = _system_differences(b.meta, spec)
    if diffs is None:
        print(f"gfbjax runup: warning: --cycles {path} records no system (written by an older gfbjax?): it is "
              f"overlaid unchecked on the run-up of system '{system}'", file=sys.stderr, flush=True)
    elif diffs:
        raise ParameterError(f"--cycles {path}: the branch was computed for another system than '{system}': "
                             + "; ".join(diffs) + " (only the grid Nx, Nz may differ)")
    return {"speed": b.lam, "stable": b.stable, "x_max": b.xmax[:, 0], "x_min": b.xmin[:, 0],
            "y_max": b.xmax[:, 1], "y_min": b.xmin[:, 1]}


#: the names in the messages of the run-up checks and TransientSettings -> the options they come from
_OPTIONS = {"accel": "--accel", "|accel|": "|--accel|", "rtol": "--rtol", "atol": "--atol",
            "samples_per_rev": "--samples-per-rev", "chunk_revs": "--chunk-revs", "h_rub": "--h-rub",
            "solver": "--solver"}

_GRID_FIELDS = ("Nx", "Nz")
_UNBALANCE_FIELDS = ("G", "e_u", "omega_r", "omega_r_unit")  # compared through the eccentricity they give


def _system_differences(meta: dict, spec: SystemSpec) -> list[str] | None:
    """``"field = branch value (branch) vs run-up value (run-up)"`` for each physical difference between the
    system a branch records in its meta and ``spec``; None when the meta records no system."""
    recorded = meta.get("spec")
    if isinstance(recorded, dict):
        mine = spec.to_dict()
        diffs = [f"{name} = {recorded.get(name)!r} (branch) vs {mine.get(name)!r} (run-up)"
                 for name in sorted(set(mine) | set(recorded))
                 if name not in _GRID_FIELDS + _UNBALANCE_FIELDS and not _same(recorded.get(name), mine.get(name))]
        e_branch = _eccentricity(recorded)
        if not _same(e_branch, spec.eccentricity_u):
            diffs.append(f"unbalance e_u = {e_branch!r} m (branch: G = {recorded.get('G')!r}, e_u = "
                         f"{recorded.get('e_u')!r}) vs {spec.eccentricity_u!r} m (run-up)")
        return diffs
    groups = meta.get("params")
    if isinstance(groups, dict):
        params = spec.nondim()
        mine = {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}
        mine = {k: v if isinstance(v, (str, int)) else float(v) for k, v in mine.items()}  # 0-d arrays -> float
        return [f"Params.{name} = {groups.get(name)!r} (branch) vs {mine.get(name)!r} (run-up)"
                for name in sorted(set(mine) | set(groups))
                if name not in _GRID_FIELDS and not _same(groups.get(name), mine.get(name))]
    return None


def _eccentricity(recorded: dict) -> float | None:
    """The unbalance eccentricity e_u [m] of a recorded spec dict (e_u, else G / omega_r, omega_r in its recorded
    omega_r_unit, rad/s when absent); None if unreadable."""
    e_u, G, omega_r = recorded.get("e_u"), recorded.get("G"), recorded.get("omega_r")
    if isinstance(e_u, (int, float)):
        return float(e_u)
    if isinstance(G, (int, float)) and isinstance(omega_r, (int, float)) and omega_r > 0:
        if recorded.get("omega_r_unit", "rad/s") == "rpm":
            omega_r = omega_r * 2 * math.pi / 60
        return G * 1e-3 / omega_r
    return None


def _same(a: object, b: object) -> bool:
    """Equal, numbers to 1e-9 relative (a JSON round trip is exact; derived values such as e_u may not be)."""
    numbers = (int, float)
    if isinstance(a, numbers) and isinstance(b, numbers) and not isinstance(a, bool) and not isinstance(b, bool):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-300)
    return a == b
