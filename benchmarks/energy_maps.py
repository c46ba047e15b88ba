"""Maps of W_cb and W_cf over (alpha_f, eta) at Omega_bar = 0.2, 0.4, 0.6 (issue 5, item 6; paper Figs. 13-14):
one batched (vmapped) Newton sweep warm-started from the reference foil's cycle (:func:`gfbjax.maps.energy_map`),
timed against a Python loop over the same points with the same start (:class:`gfbjax.design.FoilDesign`, dense
condensation as in the sweep, and the default 'auto' backend).

Usage:  python benchmarks/energy_maps.py [--nx 16 --nz 2] [--k 8] [--speeds 0.2 0.4 0.6]
Writes benchmarks/results/energy_maps.json and energy_maps.png.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gfbjax
import numpy as np

from gfbjax.design import FOIL_BOUNDS, CycleNotConverged, FoilDesign
from gfbjax.maps import energy_map

RESULTS = Path(__file__).resolve().parent / "results"


def loop(params, omega, a, e, solver):
    d = FoilDesign(params, omega, linear_solver=solver)
    start = d.evaluate(float(params.alpha_f), float(params.eta)).orbit
    d.evaluate(float(a[0]), float(e[0]), guess=start)  # compile outside the timing
    t0 = time.perf_counter()
    W = np.full((len(e), len(a)), np.nan)
    for i, ee in enumerate(e):
        for j, aa in enumerate(a):
            try:
                W[i, j] = d.evaluate(float(aa), float(ee), guess=start).W_cb
            except CycleNotConverged:
                pass
    return W, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nx", type=int, default=16)
    ap.add_argument("--nz", type=int, default=2)
    ap.add_argument("--k", type=int, default=8, help="grid points per design variable")
    ap.add_argument("--speeds", type=float, nargs="+", default=[0.2, 0.4, 0.6])
    ap.add_argument("--out", default=str(RESULTS / "energy_maps"))
    a_ = ap.parse_args()
    params = gfbjax.reference_system(Nx=a_.nx, Nz=a_.nz).nondim()
    a = np.geomspace(*FOIL_BOUNDS["alpha_f"], a_.k)
    e = np.geomspace(*FOIL_BOUNDS["eta"], a_.k)
    rows, maps = [], []
    for w in a_.speeds:
        t0 = time.perf_counter()
        m0 = energy_map(params, w, a, e)
        first = time.perf_counter() - t0
        m = energy_map(params, w, a, e)  # compiled
        Wd, td = loop(params, w, a, e, "dense")
        Wa, ta = loop(params, w, a, e, "auto")
        both = m.converged & np.isfinite(Wd)
        rows.append({"Omega_bar": w, "points": int(m.converged.size), "converged": int(m.converged.sum()),
                     "loop_converged": int(np.isfinite(Wd).sum()), "sweep_first_call_s": round(first, 2),
                     "sweep_s": round(m.seconds, 3), "loop_dense_s": round(td, 3), "loop_auto_s": round(ta, 3),
                     "max_abs_diff_W_cb": float(np.max(np.abs(m.W_cb - Wd)[both])) if both.any() else None,
                     "alpha_f": a.tolist(), "eta": e.tolist(), "W_cb": m.W_cb.tolist(), "W_cf": m.W_cf.tolist()})
        maps.append(m)
        print(f"Omega {w}: {m.converged.sum()}/{m.converged.size} converged; vmapped sweep {m.seconds:.2f} s "
              f"(first call {first:.1f} s), Python loop dense {td:.2f} s, auto {ta:.2f} s", flush=True)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(maps), figsize=(4.6 * len(maps), 7.5), squeeze=False)
    for k, m in enumerate(maps):
        for r, (W, name) in enumerate(((m.W_cb, "$W_{cb}$"), (m.W_cf, "$W_{cf}$"))):
            ax = axes[r, k]
            pc = ax.pcolormesh(m.alpha_f, m.eta, W, shading="nearest", cmap="viridis")
            fig.colorbar(pc, ax=ax)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(fr"{name} [$p_0RLc$], $\bar\Omega$ = {m.omega}", fontsize=10)
            ax.set_xlabel(r"$\alpha_f$")
            ax.set_ylabel(r"$\eta$")
    fig.tight_layout()
    out = Path(a_.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out.with_suffix(".png"), dpi=120)
    out.with_suffix(".json").write_text(json.dumps({"grid": [a_.nx, a_.nz], "rows": rows}, indent=1))
    print(f"\n{'Omega':>5} {'converged':>9} {'sweep [s]':>9} {'loop dense [s]':>14} {'loop auto [s]':>13} {'ratio':>6}")
    for r in rows:
        print(f"{r['Omega_bar']:>5} {r['converged']:>4}/{r['points']:<4} {r['sweep_s']:>9.2f} {r['loop_dense_s']:>14.2f}"
              f" {r['loop_auto_s']:>13.2f} {r['loop_dense_s'] / r['sweep_s']:>6.1f}")
    print(f"wrote {out.with_suffix('.json')}")


if __name__ == "__main__":
    main()
