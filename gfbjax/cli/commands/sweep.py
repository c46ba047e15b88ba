"""``gfbjax sweep``: a grid (or list) of designs of one system, each analysed the same way (static equilibria, the
equilibria branch and its Hopf point, the unbalance-response cycles, energy, foil optimum), serially or on Dask,
stored design by design and consolidated into one netCDF file (:mod:`gfbjax.sweep`)."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

from ... import limits
from ...params import ParameterError
from ._common import (_convert, add_step_options, add_system_options, check_chord_tol, check_option, check_range,
                      float_list, output_dir, spec_from_args, write_summary)

NAME = "sweep"

DESCRIPTION = """\
Runs the chosen analyses (--analysis) on every design of a grid (--grid, repeatable: the outer product of the
values) or of a list (--designs FILE.json), over any SystemSpec field, and collects their figures: the speed and
frequency of the first Hopf point (equilibria), the first loss of stability and the first special point of the
unbalance-response cycles (cycles), the static eccentricity, attitude and h_min (static), W_cb, W_cf (energy) and
the optimal foil (optimum) at --speeds.  Every value is checked before anything is computed.

Each finished design is written at once to --out/designs/<key>.json; running the same sweep into the same folder
again skips the designs already there (a grid extended by a value computes only the new designs); a folder that
holds a sweep of another system or other settings is refused.  Runs serially (--workers 0, the default), on a
local Dask cluster of --workers processes, or on a running Dask cluster (--scheduler).

Writes to --out: sweep.nc (xarray Dataset, netCDF-3: one dimension per swept field, one variable per figure with
its units, outcome/message per design), manifest.json, designs/*.json, sweep.json (summary) and sweep.png (a heat
map over the first two swept fields, or a line plot for one).
Exit status: 0 when every design's analyses ran, 1 when some raised (see outcome/message), 2 for invalid input.
"""

EPILOG = """\
units: speeds are dimensionless, Omega_bar = Omega t* (the bearing number); SystemSpec fields in SI or their own
dimensionless design values (alpha_f, eta, k_s_bar).

examples:
  gfbjax sweep --nx 16 --nz 2 --grid alpha_f=0.05,0.1,0.5 --grid eta=0.05,0.5 --start 0.05 --end 1
  gfbjax sweep --grid "k_s_bar=geomspace(0.3,3,4)" --analysis equilibria,cycles --N 12 --workers 2
  gfbjax sweep --grid G=1,2.5,6.3 --analysis energy --speeds 0.2,0.4 --scheduler tcp://10.0.0.5:8786
"""


def register(subparsers: Any) -> argparse.ArgumentParser:
    from ...sweep import ANALYSES

    p = subparsers.add_parser(NAME, help="grids of designs: Hopf / stability speeds, energy, optima per design, "
                                         "serial or on Dask", description=DESCRIPTION, epilog=EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    add_system_options(p, NAME)
    d = p.add_argument_group("designs")
    d.add_argument("--grid", action="append", default=[], metavar="FIELD=VALUES",
                   help="a swept SystemSpec field and its values, repeatable (outer product): comma-separated "
                        "(alpha_f=0.05,0.1,0.5), linspace(a,b,n) or geomspace(a,b,n)")
    d.add_argument("--designs", type=Path, default=None, metavar="FILE.json",
                   help="instead of --grid: a JSON list of {field: value} objects, one per design")
    a = p.add_argument_group("analyses")
    a.add_argument("--analysis", default="equilibria", metavar="NAMES",
                   help=f"comma-separated, from {', '.join(ANALYSES)} (default: %(default)s)")
    a.add_argument("--start", type=float, default=0.05, metavar="OMEGA_BAR",
                   help="start speed of the equilibria and cycles branches (default 0.05)")
    a.add_argument("--end", type=float, default=1.0, metavar="OMEGA_BAR",
                   help="end speed of the equilibria and cycles branches (default 1.0)")
    a.add_argument("--speeds", type=float_list("--speeds", limits.SPEED), default=[0.3], metavar="W1,W2",
                   help="speeds (Omega_bar) of the static, energy and optimum analyses (default 0.3)")
    a.add_argument("--w", type=float, default=0.0, help="extra specific load W/(p0 L D) of the static analysis "
                                                        "(default 0)")
    add_step_options(a, arclength=False)
    a.add_argument("--hopf-criticality", type=int, default=0, metavar="P",
                   help="continue P self-excited cycles from each located Hopf point to tell sub- from "
                        "supercritical (default 0: off; costly)")
    a.add_argument("--objective", default="W_cb", choices=("W_cb", "max_mu"),
                   help="objective of the optimum analysis (default W_cb)")
    a.add_argument("--method", default="gradient", choices=("gradient", "adam", "pattern"),
                   help="optimiser of the optimum analysis (default gradient)")
    a.add_argument("--max-iter", type=int, default=50, help="optimiser iterations per speed (default 50)")
    e = p.add_argument_group("execution")
    e.add_argument("--workers", type=int, default=0, metavar="N",
                   help="0: serial in this process (default); N: a local Dask cluster of N single-threaded "
                        "processes")
    e.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="address of a running Dask scheduler, e.g. tcp://10.0.0.5:8786 (its workers need gfbjax)")
    e.add_argument("--retry-failed", action="store_true",
                   help="compute again the stored designs whose analyses raised")
    o = p.add_argument_group("output")
    o.add_argument("--plot", default=None, metavar="VARIABLE",
                   help="variable of sweep.png (default: the first loss of stability of the cycles, else the Hopf "
                        "speed, else the first figure there is)")
    o.add_argument("--no-figures", action="store_true", help="no PNG figure")
    o.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


def _numbers(option: str, text: str) -> list[str]:
    """The value texts of ``FIELD=VALUES``: a comma list, or linspace(a,b,n) / geomspace(a,b,n) as numbers."""
    t = text.strip()
    for fn in ("linspace", "geomspace"):
        if t.lower().startswith(fn + "(") and t.endswith(")"):
            parts = [s.strip() for s in t[len(fn) + 1:-1].split(",")]
            if len(parts) != 3:
                raise ParameterError(f"{option}: {fn}(start, stop, count) takes 3 numbers, got {t!r}")
            try:
                lo, hi = float(parts[0]), float(parts[1])
            except ValueError:
                raise ParameterError(f"{option}: {fn} bounds must be numbers, got {t!r}") from None
            n = check_option(f"{option} {fn} count", _int(option, parts[2]), 1, 10**5, integer=True)
            if fn == "geomspace" and (lo <= 0 or hi <= 0):
                raise ParameterError(f"{option}: geomspace bounds must be > 0, got {t!r}")
            import numpy as np

            vals = np.linspace(lo, hi, n) if fn == "linspace" else np.geomspace(lo, hi, n)
            return [repr(float(v)) for v in vals]
    vals = [s.strip() for s in t.split(",") if s.strip()]
    if not vals:
        raise ParameterError(f"{option}: no values given")
    return vals


def _int(option: str, text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise ParameterError(f"{option}: expected an integer count, got {text!r}") from None


def parse_grid(items: list[str]) -> dict[str, list[Any]]:
    """``["alpha_f=0.5,1", "eta=linspace(0.1,0.5,3)"]`` -> ``{field: typed values}``; ParameterError naming the
    option and the field for an unknown field, a repeated field or a value of the wrong type (ranges are checked
    by :func:`gfbjax.sweep.run_sweep`)."""
    import typing

    from ...params import SystemSpec

    hints = typing.get_type_hints(SystemSpec)
    grid: dict[str, list[Any]] = {}
    for item in items:
        if "=" not in item:
            raise ParameterError(f"--grid expects FIELD=VALUES, got {item!r}")
        name, text = (s.strip() for s in item.split("=", 1))
        option = f"--grid {name}"
        if name not in hints:
            raise ParameterError(f"{option}: unknown SystemSpec field; allowed: {', '.join(hints)}")
        if name in grid:
            raise ParameterError(f"{option}: the field is given twice; give all its values in one --grid")
        vals = []
        for v in _numbers(option, text):
            try:
                vals.append(_convert(name, v, hints[name]))
            except ParameterError as exc:
                raise ParameterError(str(exc).replace(f"--set {name}", option, 1)) from None
        grid[name] = vals
    return grid


def read_designs(path: Path) -> list[dict[str, Any]]:
    """The design list of ``--designs FILE.json`` (a JSON list of objects)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ParameterError(f"--designs {str(path)!r}: no such file") from None
    except (OSError, ValueError) as exc:
        raise ParameterError(f"--designs {str(path)!r}: not a readable JSON file ({exc})") from None
    if not isinstance(data, list) or not all(isinstance(d, dict) for d in data):
        raise ParameterError(f"--designs {str(path)!r}: expected a JSON list of {{field: value}} objects")
    return data


def analyses_from_args(args: argparse.Namespace) -> list[Any]:
    """The analysis objects of ``--analysis`` with the numerics options; ParameterError naming the option."""
    from ... import sweep as sw

    check_range("--start", args.start, limits.SPEED)
    check_range("--end", args.end, limits.SPEED)
    check_range("--m", args.m, limits.COLLOCATION_M)
    check_range("--N", args.N, limits.MESH_N)
    check_option("--max-points", args.max_points, 2, 10**6, what="points", integer=True)
    check_option("--dlam-max", args.dlam_max, 0.0, None, lo_open=True, what="speed change per step")
    check_chord_tol(args.chord_tol)
    check_option("--hopf-criticality", args.hopf_criticality, 0, 10**5, what="points", integer=True)
    check_option("--max-iter", args.max_iter, 1, 10**4, what="iterations", integer=True)
    check_range("--w", args.w, limits.LOAD_W)
    names = [s.strip() for s in args.analysis.split(",") if s.strip()]
    unknown = [n for n in names if n not in sw.ANALYSES]
    if unknown or not names:
        raise ParameterError(f"--analysis {args.analysis!r}: choose from {', '.join(sw.ANALYSES)} (comma-separated)")
    if len(set(names)) != len(names):
        raise ParameterError(f"--analysis {args.analysis!r} names an analysis twice")
    if {"equilibria", "cycles"} & set(names) and args.start == args.end:
        raise ParameterError("--end must differ from --start")
    speeds = tuple(args.speeds)
    make = {
        "static": lambda: sw.Static(speeds=speeds, w=args.w),
        "equilibria": lambda: sw.Equilibria(start=args.start, end=args.end, max_points=args.max_points,
                                            criticality_points=args.hopf_criticality, hopf_N=args.N,
                                            hopf_m=args.m),
        "cycles": lambda: sw.Cycles(start=args.start, end=args.end, m=args.m, N=args.N, dlam_max=args.dlam_max,
                                    chord_tol=args.chord_tol, max_points=args.max_points),
        "energy": lambda: sw.Energy(speeds=speeds, m=args.m, N=args.N),
        "optimum": lambda: sw.Optimum(speeds=speeds, objective=args.objective, method=args.method,
                                      max_iter=args.max_iter, m=args.m, N=args.N),
    }
    return [make[n]() for n in names]


_KEY_FIGURES = (("hopf_omega_bar", "Hopf"), ("cycles_loss_omega_bar", "loss"), ("cycles_first_special", "first"),
                ("static_eccentricity", "ecc"), ("energy_W_cb", "W_cb"), ("optimum_alpha_f", "alpha_f*"),
                ("optimum_eta", "eta*"))


def _table(ds: Any, limit: int = 40) -> str:
    """One line per design: its swept values, the key figures (first speed of a per-speed one), the outcome."""
    import numpy as np

    dims = list(ds["outcome"].dims)
    flat = ds.stack(_d=dims)  # also for one dimension: a rename would take the swept field's coordinate with it
    n = flat.sizes["_d"]
    cols = [(v, label) for v, label in _KEY_FIGURES if v in ds.data_vars]
    fields = json.loads(ds.attrs.get("swept_fields", "[]"))
    lines = [f"  {'design':<28} " + " ".join(f"{label:>10}" for _, label in cols) + "  outcome"]
    for i in range(min(n, limit)):
        row = flat.isel(_d=i)
        name = " ".join(f"{f}={np.asarray(row[f]).item():.4g}" if np.issubdtype(np.asarray(row[f]).dtype, np.number)
                        else f"{f}={np.asarray(row[f]).item()}" for f in fields if f in row.coords)
        vals = []
        for v, _ in cols:
            x = np.asarray(row[v]).ravel()
            x = x[0] if x.size else math.nan
            vals.append(f"{x:>10.4g}" if isinstance(x, (float, np.floating)) else f"{str(x):>10}")
        oc = str(np.asarray(row["outcome"]).item())
        lines.append(f"  {name:<28} " + " ".join(vals) + f"  {oc}")
    if n > limit:
        lines.append(f"  ... {n - limit} more designs in sweep.nc")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    import gfbjax

    from ...sweep import design_set, run_sweep

    t0 = time.perf_counter()
    spec = spec_from_args(args)
    if args.grid and args.designs is not None:
        raise ParameterError("give --grid or --designs, not both")
    if not args.grid and args.designs is None:
        raise ParameterError("give the designs: --grid FIELD=VALUES (repeatable) or --designs FILE.json")
    grid = parse_grid(args.grid) if args.grid else None
    designs = read_designs(args.designs) if args.designs is not None else None
    analyses = analyses_from_args(args)
    if args.plot is not None:  # checked now: the figure is drawn after every design has been computed
        from ...sweep.plot import plot_variables

        if args.no_figures:
            raise ParameterError("--plot chooses the variable of sweep.png; with --no-figures there is none")
        allowed = plot_variables(analyses)
        if args.plot not in allowed:
            raise ParameterError(f"--plot {args.plot!r} is not a numeric result of --analysis {args.analysis}; "
                                 f"choose one of {', '.join(allowed)}")
    check_option("--workers", args.workers, 0, 4096, what="0: serial", integer=True)
    if args.scheduler is not None and args.workers:
        raise ParameterError("--workers starts a local cluster; with --scheduler the cluster's own workers run")
    checked = design_set(spec, grid, designs)  # every value checked before the header line and any work
    for a in analyses:
        a.check(checked.specs, [f"design {c}" for c in checked.changes])
    n = len(checked)
    out = output_dir(args)
    executor = "dask" if (args.workers or args.scheduler) else "serial"
    where = (f"Dask scheduler {args.scheduler}" if args.scheduler else
             f"local Dask cluster of {args.workers} processes" if args.workers else "serially")
    print(f"gfbjax sweep: system '{args.system}', grid Nx={spec.Nx} Nz={spec.Nz}, {n} designs x "
          f"{', '.join(a.name for a in analyses)}, {where}", flush=True)
    t1 = time.perf_counter()
    ds = run_sweep(spec, grid, designs=designs, analyses=analyses, out=out, executor=executor,
                   workers=args.workers or None, scheduler=args.scheduler, retry_failed=args.retry_failed,
                   progress=not args.quiet)
    t_run = time.perf_counter() - t1
    n_bad = int(np.sum(np.asarray(ds["outcome"]) != "ok"))
    print(f"  designs           {ds.attrs['n_designs']} ({ds.attrs['n_reused']} reused from {out}/designs, "
          f"{ds.attrs['n_computed']} computed in {t_run:.1f} s); {n_bad} with failed analyses", flush=True)
    print(_table(ds), flush=True)
    if n_bad:
        msgs = [m for m in np.asarray(ds["message"]).ravel() if m]
        print(f"  first failure     {msgs[0]}" if msgs else "", flush=True)

    figures: list[str] = []
    t2 = time.perf_counter()
    if not args.no_figures:
        import matplotlib.pyplot as plt

        from ...sweep.plot import plot_sweep

        try:
            fig = plot_sweep(ds, args.plot, path=out / "sweep.png")
        except ValueError as exc:
            raise ParameterError(f"--plot: {exc}") from None
        plt.close(fig)
        figures.append("sweep.png")
    t_fig = time.perf_counter() - t2
    data = {
        "command": NAME, "gfbjax_version": gfbjax.__version__,
        "system": {"name": args.system, "spec": spec.to_dict(), "t_star_s": spec.t_star},
        "designs": {"kind": ds.attrs["designs_kind"], "fields": json.loads(ds.attrs["swept_fields"]),
                    "count": int(ds.attrs["n_designs"]), "reused": int(ds.attrs["n_reused"]),
                    "computed": int(ds.attrs["n_computed"]), "with_failed_analyses": n_bad},
        "analyses": json.loads(ds.attrs["analyses_settings"]),
        "execution": {"executor": executor, "workers": args.workers, "scheduler": args.scheduler},
        "files": ["sweep.nc", "manifest.json", "designs/", "sweep.json"] + figures,
        "timings_s": {"setup": t1 - t0, "sweep": t_run, "figures": t_fig, "total": time.perf_counter() - t0},
    }
    write_summary(out, "sweep.json", data)
    return 1 if n_bad else 0
