"""Cost of a special point's error bar (its relocations on two other meshes) and the kernels a branch compiles.

A short branch of the reference system across its NS (Omega_bar 0.36 -> 0.40, default settings, 6 points), twice
in one fresh process with the persistent compilation cache off.  For each relocation (the mesh with every interval
halved, then the mesh staggered by half an interval; ``cont._localise._relocated_shift``): the corrections it
took, the shift of the zero in Omega_bar and the wall time.  For each branch: the kernels XLA compiled (JAX's
``/jax/core/compile/backend_compile_duration`` events) and the wall time.  The second branch compiles nothing when
every kernel serves every call it gets (a weakly typed scalar, e.g., makes a kernel compile again).

    python benchmarks/special_point_relocation.py      # ~1.5 min on a 2-core CPU
"""
from __future__ import annotations

import os

os.environ["GFBJAX_CACHE_DIR"] = "off"  # every compilation counted, none loaded from an earlier run

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import gfbjax  # noqa: E402
import jax  # noqa: E402
from gfbjax.analyses.cycles import continue_gfb_cycles, default_cycle_settings  # noqa: E402
from gfbjax.cont import _localise  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
MESHES = ("halved", "staggered")  # the order of the cycles' other_discretisations


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--start", type=float, default=0.36, help="Omega_bar at the branch's start")
    ap.add_argument("--end", type=float, default=0.40, help="Omega_bar at its end (the NS lies between)")
    ap.add_argument("--out", default=str(RESULTS / "special_point_relocation.json"),
                    help="result file (default: the committed one in benchmarks/results)")
    a = ap.parse_args()

    compiled = [0]
    jax.monitoring.register_event_duration_secs_listener(
        lambda name, *_, **__: compiled.__setitem__(0, compiled[0] + (name == "/jax/core/compile/backend_compile_duration")))
    relocations: list[dict] = []
    original = _localise._relocated_shift

    def counted(run, f, X2, t2, *args, **kwargs):
        c, n = run.curve, [0]
        correct = c.correct

        def correct_counted(*ca, **ck):
            n[0] += 1
            return correct(*ca, **ck)

        c.correct = correct_counted
        t0 = time.perf_counter()
        try:
            shift = original(run, f, X2, t2, *args, **kwargs)
        finally:
            del c.correct
        relocations.append({"kind": f.kind, "corrections": n[0], "shift": float(shift),
                            "seconds": round(time.perf_counter() - t0, 2)})
        return shift

    _localise._relocated_shift = counted
    params = gfbjax.reference_system().nondim()
    runs = []
    for label in ("first", "second"):
        relocations.clear()
        before, t0 = compiled[0], time.perf_counter()
        branch = continue_gfb_cycles(params, a.start, a.end, default_cycle_settings(max_points=6))
        runs.append({"run": label, "seconds": round(time.perf_counter() - t0, 2), "compiled": compiled[0] - before,
                     "points": len(branch),
                     "special": [{"type": p.type, "Omega_bar": float(p.lam), "error": float(p.lam_error)}
                                 for p in branch.special],
                     "relocations": [dict(r, mesh=MESHES[i % 2]) for i, r in enumerate(relocations)]})

    print(f"{'branch':<8} {'s':>7} {'kernels compiled':>17}  special points")
    for r in runs:
        sp = ", ".join(f"{p['type']} {p['Omega_bar']:.5f} +- {p['error']:.1e}" for p in r["special"])
        print(f"{r['run']:<8} {r['seconds']:>7.1f} {r['compiled']:>17}  {sp}")
    print(f"\n{'branch':<8} {'point':<6} {'mesh':<10} {'corrections':>11} {'shift':>12} {'s':>6}")
    for r in runs:
        for x in r["relocations"]:
            print(f"{r['run']:<8} {x['kind']:<6} {x['mesh']:<10} {x['corrections']:>11} {x['shift']:>12.5e} "
                  f"{x['seconds']:>6.1f}")
    rec = {"system": "reference", "range": [a.start, a.end], "settings": "default_cycle_settings(max_points=6)",
           "runs": runs, "machine": {"platform": platform.platform(), "cpus": os.cpu_count()},
           "versions": {"jax": jax.__version__}, "note": "wall times on a 2-core machine"}
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(rec, indent=1))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
