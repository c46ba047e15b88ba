"""The headline result (issue 5, item 5; paper Figs. 16-19): bifurcation-free speed range of the fixed reference
foil against that of the optimised foil schedule, for the paper's design cases.

Cases: k_s 0.3, 1, 3 with G2.5 (Figs. 16, 18) and G1, G2.5, G6.3 with k_s 1 (Figs. 17, 19).  For each:

* fixed design: the synchronous cycle branch from ``--start`` upward with the reference foil (alpha_f 0.1,
  eta 0.05); its first bifurcation (or first unstable point) ends the bifurcation-free range;
* optimised schedule (:func:`gfbjax.design.schedule.optimized_continuation`, steps a-f): at each speed, starting from the
  previous optimum and cycle, the foil minimising max|mu| (OBJ2) inside the bounds of Appendix A2; the march
  stops at the first speed where the best admissible foil leaves the cycle unstable.

Both on the same grid and the smoothed Gumbel condition (``gumbel_width``; see benchmarks/foil_optimizers.py).

Usage:  python benchmarks/optimized_continuation.py [--nx 24 --nz 4] [--start 0.1 --end 1.2 --step 0.05]
Writes benchmarks/results/optimized_continuation.json and .png.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gfbjax

from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings
from gfbjax.design.schedule import optimized_continuation
from gfbjax.plot.branch import plot_schedule

RESULTS = Path(__file__).resolve().parent / "results"
CASES = {"ks0.3 G2.5": dict(k_s_bar=0.3, G=2.5), "ks1 G2.5": dict(G=2.5), "ks3 G2.5": dict(k_s_bar=3.0, G=2.5),
         "ks1 G1": dict(G=1.0), "ks1 G6.3": dict(G=6.3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nx", type=int, default=24)
    ap.add_argument("--nz", type=int, default=4)
    ap.add_argument("--gumbel-width", type=float, default=1e-3)
    ap.add_argument("--start", type=float, default=0.1)
    ap.add_argument("--end", type=float, default=1.2)
    ap.add_argument("--step", type=float, default=0.05)
    ap.add_argument("--objective", default="max_mu")
    ap.add_argument("--cases", nargs="+", default=list(CASES))
    ap.add_argument("--out", default=str(RESULTS / "optimized_continuation"))
    a = ap.parse_args()
    rows, panels = [], []
    for name in a.cases:
        params = gfbjax.reference_system(Nx=a.nx, Nz=a.nz, gumbel_width=a.gumbel_width, **CASES[name]).nondim()
        t0 = time.perf_counter()
        b = continue_gfb_cycles(params, a.start, a.end, default_cycle_settings())
        t_fixed = time.perf_counter() - t0
        first_bif = next((s for s in b.special), None)
        first_unstable = next((float(b.lam[i]) for i in range(len(b)) if not b.stable[i]), None)
        fixed_to = float(first_bif.lam) if first_bif is not None else first_unstable
        sched = optimized_continuation(params, a.start, a.end, a.step, objective=a.objective, progress=True)
        opt_to = sched.bifurcation_free_to
        row = {"case": name, "fixed": {"first_bifurcation": None if first_bif is None else
                                       {"type": first_bif.type, "Omega_bar": float(first_bif.lam)},
                                       "first_unstable_point": first_unstable, "bifurcation_free_to": fixed_to,
                                       "branch_outcome": str(b.outcome), "branch_message": b.message,
                                       "seconds": round(t_fixed, 1)},
               "optimised": sched.to_dict(),
               "range_ratio": (opt_to - a.start) / (fixed_to - a.start) if (opt_to and fixed_to) else None,
               "upper_speed_ratio": opt_to / fixed_to if (opt_to and fixed_to) else None}
        rows.append(row)
        panels.append((name, sched))
        print(f"{name}: fixed foil bifurcation-free to {fixed_to}; optimised schedule to {opt_to} "
              f"({sched.outcome}: {sched.message}); {sched.n_solves} solves, {sched.seconds:.0f} s", flush=True)
        Path(a.out).with_suffix(".json").write_text(json.dumps(
            {"grid": [a.nx, a.nz], "gumbel_width": a.gumbel_width, "start": a.start, "step": a.step,
             "objective": a.objective, "cases": rows}, indent=1))
    plot_schedule(panels, path=Path(a.out).with_suffix(".png"))
    print(f"\n{'case':<11} {'fixed: free to':>15} {'optimised: free to':>19} {'upper-speed ratio':>18}")
    for r in rows:
        f = lambda v: "-" if v is None else f"{v:.3f}"
        print(f"{r['case']:<11} {f(r['fixed']['bifurcation_free_to']):>15} "
              f"{f(r['optimised']['bifurcation_free_to']):>19} {f(r['upper_speed_ratio']):>18}")


if __name__ == "__main__":
    main()
