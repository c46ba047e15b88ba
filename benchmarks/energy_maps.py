"""Maps of W_cb and W_cf over (alpha_f, eta) at Omega_bar = 0.2, 0.4, 0.6 (issue 5, item 6; paper Figs. 13-14):
one batched (vmapped) Newton sweep warm-started from the reference foil's cycle (:func:`gfbjax.design.maps.energy_map`),
timed against a Python loop over the same points with the same start and the same dense Newton corrector
(:func:`gfbjax.design.maps.energy_map_loop`).  Both runs are timed after compilation.

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

from gfbjax.design.evaluate import FOIL_BOUNDS
from gfbjax.design.maps import energy_map, energy_map_loop

RESULTS = Path(__file__).resolve().parent / "results"


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
        energy_map(params, w, a, e)
        first = time.perf_counter() - t0
        m = energy_map(params, w, a, e)  # compiled: the timed sweep
        energy_map_loop(params, w, a[:1], e[:1])  # compiles the loop's kernels
        lp = energy_map_loop(params, w, a, e)
        both = m.converged & lp.converged
        rows.append({"Omega_bar": w, "points": int(m.converged.size), "converged": int(m.converged.sum()),
                     "loop_converged": int(lp.converged.sum()), "agree_converged": bool(np.all(m.converged == lp.converged)),
                     "sweep_first_call_s": round(first, 2), "sweep_s": round(m.seconds, 3),
                     "loop_s": round(lp.seconds, 3), "sweep_member_steps": m.member_steps,
                     "loop_steps": lp.member_steps,
                     "max_abs_diff_W_cb": float(np.max(np.abs(m.W_cb - lp.W_cb)[both])) if both.any() else None,
                     "alpha_f": a.tolist(), "eta": e.tolist(), "W_cb": m.W_cb.tolist(), "W_cf": m.W_cf.tolist()})
        maps.append(m)
        print(f"Omega {w}: {m.converged.sum()}/{m.converged.size} converged (loop {lp.converged.sum()}); vmapped "
              f"sweep {m.seconds:.2f} s ({m.member_steps} member-steps, first call {first:.1f} s), Python loop "
              f"{lp.seconds:.2f} s ({lp.member_steps} steps)", flush=True)
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
    print(f"\n{'Omega':>5} {'converged':>9} {'sweep [s]':>9} {'loop [s]':>9} {'loop/sweep':>10} "
          f"{'ms/step sweep':>13} {'ms/step loop':>12} {'max |dW_cb|':>11}")
    for r in rows:
        print(f"{r['Omega_bar']:>5} {r['converged']:>4}/{r['points']:<4} {r['sweep_s']:>9.2f} {r['loop_s']:>9.2f}"
              f" {r['loop_s'] / r['sweep_s']:>10.2f} {1e3 * r['sweep_s'] / r['sweep_member_steps']:>13.1f}"
              f" {1e3 * r['loop_s'] / r['loop_steps']:>12.1f} {r['max_abs_diff_W_cb'] or float('nan'):>11.1e}")
    print(f"wrote {out.with_suffix('.json')}")


if __name__ == "__main__":
    main()
