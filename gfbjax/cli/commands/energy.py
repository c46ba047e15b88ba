"""``gfbjax energy``: energy flow along the branch of unbalance-response limit cycles (paper Sect. 3.3, Eq. 23-24,
Fig. 12): per cycle the work of the unbalance force W_fu, of the journals on the gas films W_B, the foil-damper
dissipation W_cf and the net gas-film dissipation W_cb = W_B - W_cf."""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from ...cont import Outcome
from ...limits import NoSolutionError
from pathlib import Path
from typing import Any

from . import cycles as _cycles
from ._checkpoints import interrupted_status, prepare_run
from ._common import output_dir, traced_params, work_unit_J, write_summary

NAME = "energy"

DESCRIPTION = """\
Energy flow of the synchronous (1X) limit cycles of the unbalanced rotor along the speed Omega_bar (paper
Sect. 3.3, Eq. 23-24, Fig. 12).  The branch is continued exactly as by 'gfbjax cycles' (same options), with the
collocation states of every point kept; the works per cycle [p0 R L c] follow by the collocation quadrature:

  W_fu  work of the unbalance force on the disc (energy fed into the rotor),
  W_B   work the journals do on their gas films (both bearings),
  W_cf  dissipation in the bump-foil dampers,
  W_cb  = W_B - W_cf, the net dissipation in the gas films (negative: the films feed the whirl).

The rotor is conservative, so W_fu = W_B on every periodic solution: their largest relative difference along the
branch is reported as a check (rounding level on a converged branch).

Writes to --out: branch.npz + branch.json (the branch with its states, gfbjax.cont.Branch.load), energy.json
(per point Omega_bar, stability, W_fu, W_B, W_cf, W_cb; the Neimark-Sacker speeds; the speeds where W_cb changes
sign; the identity error; timings) and energy.png (W_fu, W_cf, W_cb against speed, stable solid, unstable dashed,
NS points and W_cb = 0 marked).
Exit status: 0 when the branch got to --end; 1 when it stopped short of it (the points computed are still
written); 2 for invalid input; 130 when interrupted (continue with --resume).
"""

EPILOG = """\
units: speeds are dimensionless, Omega_bar = Omega t* (the bearing number); works per cycle in p0 R L c.
Sign convention (docs/model.md): positive = energy leaving the rotor into the films and foils.

examples:
  gfbjax energy                                   reference system, Omega_bar 0.05 -> 1.0
  gfbjax energy --system ks3 --nx 24 --nz 3       a design variation of the paper's Fig. 12 on a coarser grid
  gfbjax energy --start 0.3 --end 0.45 --dlam-max 0.005
"""


def _cycle_options() -> argparse.ArgumentParser:
    """The options of ``gfbjax cycles`` (system, speed range, numerics, output) as a parent parser: this command
    takes exactly the same ones, with the same defaults and checks.  A private instance, so that changing its
    defaults (``--out``) leaves the real ``cycles`` command alone."""
    return _cycles.register(argparse.ArgumentParser(add_help=False).add_subparsers())


def register(subparsers: Any) -> argparse.ArgumentParser:
    p = subparsers.add_parser(NAME, help="energy flow of the limit cycles vs speed: W_fu, W_B, W_cf, W_cb "
                                         "(paper Fig. 12)",
                              description=DESCRIPTION, epilog=EPILOG, parents=[_cycle_options()], add_help=False,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--branch", type=Path, default=None, metavar="FILE",
                   help="compute the works on a saved branch of unbalance-response cycles (branch.npz of 'gfbjax "
                        "cycles' or 'gfbjax energy', which keep the states) instead of continuing one; its system "
                        "and settings come from the file")
    p.set_defaults(func=run, out=Path("results") / NAME)
    return p


def _saved_branch(args: argparse.Namespace) -> tuple[Any, Any, Any]:
    """(branch, spec, params) of ``--branch``; ParameterError for a file that is not a GFB cycle branch with
    states, or when system or numerics options are given with it."""
    from ...cont import Branch, BranchFileError
    from ...params import ParameterError, SystemSpec

    given = [opt for opt, dest in (("--system", "system"), ("--set", "overrides"), ("--preset", "preset"),
                                   ("--nx", "nx"), ("--nz", "nz"), ("--start", "start"), ("--end", "end"),
                                   ("--N", "N"), ("--m", "m"), ("--ds", "ds"), ("--ds-max", "ds_max"),
                                   ("--dlam-max", "dlam_max"), ("--chord-tol", "chord_tol"),
                                   ("--max-points", "max_points"), ("--resume", "resume"), ("--fresh", "fresh"),
                                   ("--h-rub-um", "h_rub_um"),
                                   ("--on-contact", "on_contact"))
             if getattr(args, dest, None) != args.option_default(dest)]
    if given:
        raise ParameterError(f"--branch {args.branch}: the system and the settings come from the file; do not give "
                             f"{', '.join(given)}")
    try:
        branch = Branch.load(args.branch)
    except BranchFileError as exc:
        raise ParameterError(f"--branch: {exc}") from None
    meta = branch.meta or {}
    if branch.kind != "cycles" or meta.get("problem") != "unbalance_response" or "spec" not in meta:
        raise ParameterError(f"--branch {args.branch}: not a branch of unbalance-response cycles written by gfbjax "
                             f"with its system (kind {branch.kind!r}, problem {meta.get('problem')!r})")
    if branch.states is None:
        raise ParameterError(f"--branch {args.branch}: the file holds no collocation states (it was saved without "
                             "save_states); rerun 'gfbjax cycles', which keeps them")
    names = {f.name for f in dataclasses.fields(SystemSpec)}
    spec = SystemSpec(**{k: v for k, v in meta["spec"].items() if k in names})
    return branch, spec, traced_params(spec)


def identity_error(W_fu: Any, W_B: Any) -> float:
    """Largest relative difference max |W_fu - W_B| / |W_fu| over the points (nan without points)."""
    import numpy as np

    W_fu, W_B = np.asarray(W_fu, float), np.asarray(W_B, float)
    if W_fu.size == 0:
        return math.nan
    return float(np.max(np.abs(W_fu - W_B) / np.maximum(np.abs(W_fu), 1e-300)))


def run(args: argparse.Namespace) -> int:
    import numpy as np

    import gfbjax

    from ...analyses.cycles import continue_gfb_cycles
    from ...analyses.energy import CycleEnergy, branch_energy, sign_changes

    t0 = time.perf_counter()
    ck = None
    if args.branch is not None:
        branch, spec, params = _saved_branch(args)
        out = output_dir(args)
        settings = None
        lam = np.asarray(branch.lam, float)
        args.start, args.end = (float(lam[0]), float(lam[-1])) if len(lam) else (math.nan, math.nan)
        args.system = str(args.branch)
        print(f"gfbjax energy: branch {args.branch} ({len(branch)} points, grid Nx={spec.Nx} Nz={spec.Nz})",
              flush=True)
        t1 = time.perf_counter()
        ok = branch.outcome is Outcome.REACHED_END
    else:
        # the works need the orbits: states are kept
        args, spec, settings, out, params, contact, ck = prepare_run(
            args, NAME, lambda a: dataclasses.replace(_cycles._settings(a), save_states=True))
        print(f"gfbjax energy: system '{args.system}', grid Nx={spec.Nx} Nz={spec.Nz}, collocation N={settings.N} "
              f"m={settings.m}, Omega_bar {args.start:g} -> {args.end:g}", flush=True)
        t1 = time.perf_counter()
        progress = _cycles._SpeedBar(args.start, args.end, not args.quiet)
        try:
            branch = continue_gfb_cycles(params, args.start, args.end, settings, callback=progress,
                                         spec=spec, checkpoint=ck, **contact)
        except NoSolutionError as exc:  # no static equilibrium at the start speed: nothing to write
            print(f"gfbjax energy: {exc}", flush=True)
            return 1
        finally:
            progress.close()
        ok = _cycles.reached_end(branch, args.start, args.end)
        branch.save(out / "branch")
    t_cont = time.perf_counter() - t1

    t2 = time.perf_counter()
    if len(branch):
        E = branch_energy(branch, params)
    else:
        E = CycleEnergy(*(np.zeros(0) for _ in range(4)))
    t_energy = time.perf_counter() - t2
    lam = np.asarray(branch.lam, float)
    stable = np.asarray(branch.stable, bool)
    ns = [s.lam for s in branch.special_of("NS")]
    zc = sign_changes(lam, E.W_cb)
    ident = identity_error(E.W_fu, E.W_B)

    def speeds(vals: list[float]) -> str:
        return ", ".join(f"{v:.4f} ({spec.rpm(v):.0f} rpm)" for v in vals) if vals else "none"

    n_stable = int(np.sum(stable))
    print("\n".join([
        f"  branch            {len(branch)} points ({n_stable} stable), ended: {branch.outcome} ({branch.message})"
        + ("" if ok else "  (before the end of the range)"),
        f"  NS speeds         {speeds(ns)}",
        "  W_cb sign changes " + (", ".join(f"{c['Omega_bar']:.4f} ({c['from']} -> {'-' if c['from'] == '+' else '+'})"
                                            for c in zc) if zc else "none"),
        f"  identity error    max |W_fu - W_B| / |W_fu| = {ident:.2e}",
        f"  time              continuation {t_cont:.1f} s, works {t_energy:.1f} s",
    ]), flush=True)

    figures: list[str] = []
    if not args.no_figures and len(branch):
        import matplotlib.pyplot as plt

        from ...plot.branch import plot_energy

        label = (f"branch {args.branch}" if settings is None else
                 f"system '{args.system}' (Nx={spec.Nx}, Nz={spec.Nz}, N={settings.N}, m={settings.m})")
        fig = plot_energy([(label, branch, E)], spec=spec, path=out / "energy.png")
        plt.close(fig)
        figures.append("energy.png")

    data = {
        "command": NAME, "gfbjax_version": gfbjax.__version__, "outcome": str(branch.outcome), "message": branch.message,
        "range": {"start": args.start, "end": args.end, "reached_end": ok},
        "system": {"name": args.system, "spec": spec.to_dict(), "t_star_s": spec.t_star},
        "settings": ({"branch_file": str(args.branch)} if settings is None else
                     {k: getattr(settings, k) for k in ("m", "N", "ds", "ds_max", "dlam_max", "chord_tol", "max_points",
                                                        "locate", "save_states")}),
        "units": {"speed": "Omega_bar", "work": "p0 R L c per cycle", "rpm": "rev/min", "W_*_J": "J per cycle",
                  "work_unit_J": work_unit_J(spec)},
        "points": [{"Omega_bar": float(lam[i]), "rpm": spec.rpm(float(lam[i])), "stable": bool(stable[i]),
                    "W_fu": float(E.W_fu[i]), "W_B": float(E.W_B[i]), "W_cf": float(E.W_cf[i]),
                    "W_cb": float(E.W_cb[i]),
                    **{f"{k}_J": float(getattr(E, k)[i]) * work_unit_J(spec) for k in ("W_fu", "W_B", "W_cf", "W_cb")}}
                   for i in range(len(lam))],
        "NS_Omega_bar": ns,
        "W_cb_sign_changes": zc,
        "max_rel_identity_error": ident,
        "special": _cycles.special_summary(branch, spec),
        "files": (["branch.npz", "branch.json"] if settings is not None else []) + ["energy.json"] + figures,
        "timings_s": {"setup": t1 - t0, "continuation": t_cont, "energy": t_energy,
                      "total": time.perf_counter() - t0},
    }
    write_summary(out, "energy.json", data)
    return interrupted_status(branch, ok, out, ck, NAME)
