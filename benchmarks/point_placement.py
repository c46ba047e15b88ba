"""Point placement on the reference branch: the chord test (``chord_tol``, the default) against a fixed speed step.

Both branches run in one process after a warm-up that compiles every kernel (the chord branch once, untimed: a
3-point warm-up, used until session 16, left the kernels that only the NS localisation needs to the first timed
branch), Omega_bar 0.05 -> 1.0 on the default grid, as ``gfbjax cycles`` computes them.  Each is compared with the other as a plot would show it: every point of
one branch against the straight lines through the points of the other, in the plane of Omega_bar and each recorded
component's max and min, each scaled by its range over the fixed-step branch.  The distance is measured along the
plotted quantity at the same speed (vertical in the plot), so it also holds between two points of the other branch
where both curves are smooth; it includes the two branches' own discretisation differences (each re-meshes at its
own points), which is why it does not fall to zero.

Usage:  python benchmarks/point_placement.py [--chord-tol 0.01 --dlam-max 0.1] [--fixed-dlam 0.02]
Writes benchmarks/results/point_placement.json and prints a table.
"""
from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import gfbjax  # noqa: F401  (process defaults: XLA flags, x64) before any JAX work
import jax
import numpy as np

from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings
from cycle_branch import add_branch_arguments  # this folder, as the script is run

RESULTS = Path(__file__).resolve().parent / "results"


def plotted(branch) -> np.ndarray:
    """(points, 1 + 2k): Omega_bar, then the recorded components' max and min, as the branch plots show them."""
    return np.concatenate([branch.lam[:, None], branch.xmax, branch.xmin], axis=1)


def gaps(points: np.ndarray, other: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """For each row of ``points`` inside the speed range of ``other``: the largest distance, over the plotted
    quantities scaled by ``scale``, from the piecewise-linear interpolation of ``other`` at the same speed."""
    order = np.argsort(other[:, 0])
    o = other[order]
    inside = (points[:, 0] >= o[0, 0]) & (points[:, 0] <= o[-1, 0])
    out = []
    for p in points[inside]:
        line = np.array([np.interp(p[0], o[:, 0], o[:, j]) for j in range(1, o.shape[1])])
        out.append(np.max(np.abs(line - p[1:]) / scale[1:]))
    return np.array(out)


def run(params, start, end, settings) -> tuple[object, float]:
    t0 = time.perf_counter()
    b = continue_gfb_cycles(params, start, end, settings)
    return b, time.perf_counter() - t0


def summary(b, t: float) -> dict:
    ns = [{"Omega_bar": float(s.lam), "error": float(s.lam_error)} for s in b.special if s.type == "NS"]
    return {"points": len(b), "branch_s": round(t, 2), "per_point_s": round(t / len(b), 3),
            "newton_iterations": int(np.sum(b.newton_iterations)), "flagged_points": int(np.sum(b.flagged)),
            "reached": float(b.lam[-1]), "outcome": str(b.outcome), "NS": ns,
            "special": [s.type for s in b.special], "Omega_bar": [round(float(v), 5) for v in b.lam]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_branch_arguments(ap)
    ap.add_argument("--fixed-dlam", type=float, default=0.02, help="speed step of the fixed-step branch")
    ap.add_argument("--out", default=str(RESULTS / "point_placement.json"))
    a = ap.parse_args()

    params = gfbjax.reference_system(Nx=a.nx, Nz=a.nz).nondim()
    chord_settings = default_cycle_settings(dlam_max=a.dlam_max, chord_tol=a.chord_tol)
    _, t_warm = run(params, a.start, a.end, chord_settings)
    chord, t_chord = run(params, a.start, a.end, chord_settings)
    t_compile = t_warm - t_chord
    fixed, t_fixed = run(params, a.start, a.end, default_cycle_settings(dlam_max=a.fixed_dlam, chord_tol=float("inf")))

    P_c, P_f = plotted(chord), plotted(fixed)
    scale = np.ptp(P_f, axis=0)
    g_fc, g_cf = gaps(P_f, P_c, scale), gaps(P_c, P_f, scale)
    rec = {
        "system": "reference", "Nx": a.nx, "Nz": a.nz, "range": [a.start, a.end],
        "compile_s": round(t_compile, 2),  # the warm-up branch less the timed one
        "chord": {"chord_tol": a.chord_tol, "dlam_max": a.dlam_max, **summary(chord, t_chord)},
        "fixed": {"chord_tol": "inf", "dlam_max": a.fixed_dlam, **summary(fixed, t_fixed)},
        "time_ratio_fixed_over_chord": round(t_fixed / t_chord, 2),
        "fixed_points_from_chord_lines": {"max": float(np.max(g_fc)), "mean": float(np.mean(g_fc)),
                                          "at_Omega_bar": float(P_f[np.argmax(g_fc), 0])},
        "chord_points_from_fixed_lines": {"max": float(np.max(g_cf)), "mean": float(np.mean(g_cf))},
        "machine": {"platform": platform.platform(), "cpus": __import__("os").cpu_count()},
        "versions": {"jax": jax.__version__, "gfbjax": gfbjax.__version__},
        "note": "wall times on a 2-core machine; distances relative to each plotted quantity's range",
    }
    RESULTS.mkdir(exist_ok=True)
    Path(a.out).write_text(json.dumps(rec, indent=1))
    rows = [("", "chord test", "fixed step"),
            ("settings", f"chord_tol {a.chord_tol:g}, dlam_max {a.dlam_max:g}", f"dlam_max {a.fixed_dlam:g}"),
            ("points", len(chord), len(fixed)),
            ("branch after compilation [s]", f"{t_chord:.1f}", f"{t_fixed:.1f}"),
            ("Newton iterations", rec["chord"]["newton_iterations"], rec["fixed"]["newton_iterations"]),
            ("flagged points", rec["chord"]["flagged_points"], rec["fixed"]["flagged_points"]),
            ("NS", *(", ".join(f"{d['Omega_bar']:.5f} +- {d['error']:.0e}" for d in r["NS"]) or "-"
                     for r in (rec["chord"], rec["fixed"])))]
    for r in rows:
        print(f"{str(r[0]):32s} {str(r[1]):36s} {r[2]}")
    print(f"time ratio fixed / chord: {t_fixed / t_chord:.2f}")
    print(f"fixed-step points from the chord branch's lines: max {np.max(g_fc):.4f} (at Omega_bar "
          f"{P_f[np.argmax(g_fc), 0]:.3f}), mean {np.mean(g_fc):.4f} of the ranges")
    print(f"chord points from the fixed-step branch's lines: max {np.max(g_cf):.4f}, mean {np.mean(g_cf):.4f}")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
