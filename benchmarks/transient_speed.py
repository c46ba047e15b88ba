"""Simulated revolutions per wall-second at the default grid (SystemSpec defaults): diffrax (Kvaerno5 /
Kvaerno3, sparse-coloured or dense Jacobian) against scipy.integrate.solve_ivp (Radau, BDF) with the exact jitted
Jacobian, same system, rtol/atol and span, in the same run.  End states are compared with a tight diffrax reference
(rtol 1e-9) to check matched accuracy.  Writes benchmarks/results/transient_speed.json.

    python benchmarks/transient_speed.py [--speed 0.5] [--revs 3] [--rtol 1e-6] [--atol 1e-8]

Wall times on a shared machine are noisy; CPU times (process time) are reported beside them.  The diffrax rows
exclude compilation (a first, identical run compiles); scipy's rows exclude the jit of f and J.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # before numpy/scipy/jax load LAPACK: multithreaded 281x281 LU is slower

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import gfbjax  # noqa: E402
from gfbjax.model import runup_vector_field  # noqa: E402
from gfbjax.analyses.transient import TransientSettings, as_traced, default_initial_state, simulate  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speed", type=float, default=0.5)
    ap.add_argument("--revs", type=float, default=3.0)
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--atol", type=float, default=1e-8)
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "transient_speed.json")
    args = ap.parse_args()

    spec = gfbjax.reference_system()
    params = as_traced(spec.nondim())
    om = args.speed
    s0, _ = default_initial_state(params, om)
    tau_end = args.revs * 2 * math.pi / om
    rows = []

    def diffrax_row(name, **kw):
        st = TransientSettings(rtol=kw.pop("rtol", args.rtol), atol=kw.pop("atol", args.atol),
                               chunk_revs=args.revs, **kw)
        simulate(params, om, tau_end=tau_end, s0=s0, settings=st)  # compile
        t0, c0 = time.perf_counter(), time.process_time()
        r = simulate(params, om, tau_end=tau_end, s0=s0, settings=st)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        row = dict(method=name, rtol=st.rtol, atol=st.atol, steps=r.stats["steps"], rejected=r.stats["rejected"],
                   nfev=None, njev=r.stats["steps"], wall_s=wall, cpu_s=cpu, end=np.asarray(r.final_state))
        print(f"{name:34s} {wall:7.2f} s wall {cpu:7.2f} s cpu  {r.stats['steps']} steps", flush=True)
        return row

    ref = diffrax_row("diffrax Kvaerno5 (reference)", rtol=1e-9, atol=1e-11)
    rows.append(diffrax_row("diffrax Kvaerno5 colored-J"))
    rows.append(diffrax_row("diffrax Kvaerno5 colored-J rtol*10", rtol=10 * args.rtol, atol=10 * args.atol))
    rows.append(diffrax_row("diffrax Kvaerno3 colored-J", solver="kvaerno3"))
    rows.append(diffrax_row("diffrax Kvaerno5 dense-J (VeryChord)", jacobian="dense"))

    f = jax.jit(lambda t, y: runup_vector_field(t, y, params, om, 0.0))
    J = jax.jit(jax.jacfwd(lambda t, y: runup_vector_field(t, y, params, om, 0.0), argnums=1))
    y0 = jnp.asarray(s0)
    f(0.0, y0).block_until_ready()
    J(0.0, y0).block_until_ready()
    fun = lambda t, y: np.asarray(f(t, y))  # noqa: E731
    jac = lambda t, y: np.asarray(J(t, y))  # noqa: E731
    for method in ("Radau", "BDF"):
        t0, c0 = time.perf_counter(), time.process_time()
        sol = solve_ivp(fun, (0.0, tau_end), np.asarray(s0), method=method, jac=jac, rtol=args.rtol, atol=args.atol)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        print(f"scipy {method:28s} {wall:7.2f} s wall {cpu:7.2f} s cpu  {sol.t.size - 1} steps "
              f"({sol.nfev} f, {sol.njev} J, {sol.nlu} LU) {sol.message}", flush=True)
        rows.append(dict(method=f"scipy solve_ivp {method} (exact jitted J)", rtol=args.rtol, atol=args.atol,
                         steps=int(sol.t.size - 1), rejected=None, nfev=int(sol.nfev), njev=int(sol.njev),
                         wall_s=wall, cpu_s=cpu, end=sol.y[:, -1]))

    n_rotor = 8
    out_rows = []
    print(f"\n{'method':44s} {'rtol':>7s} {'steps':>6s} {'wall s':>8s} {'cpu s':>8s} {'steps/s':>8s} "
          f"{'rev/s':>7s} {'rev/cpu-s':>9s} {'err rotor':>9s} {'err all':>9s}")
    for r in rows:
        e_rot = float(np.abs(r["end"][-n_rotor:] - ref["end"][-n_rotor:]).max())
        e_all = float(np.abs(r["end"] - ref["end"]).max())
        d = {k: v for k, v in r.items() if k != "end"}
        d.update(steps_per_s=r["steps"] / r["wall_s"], revs_per_s=args.revs / r["wall_s"],
                 revs_per_cpu_s=args.revs / r["cpu_s"], end_error_rotor=e_rot, end_error_all=e_all)
        out_rows.append(d)
        print(f"{d['method']:44s} {d['rtol']:7.0e} {d['steps']:6d} {d['wall_s']:8.2f} {d['cpu_s']:8.2f} "
              f"{d['steps_per_s']:8.1f} {d['revs_per_s']:7.3f} {d['revs_per_cpu_s']:9.3f} {e_rot:9.1e} {e_all:9.1e}")
    data = dict(system="reference (SystemSpec defaults)", Nx=spec.Nx, Nz=spec.Nz, n_states=int(s0.size),
                speed=om, revolutions=args.revs, tau_end=tau_end, rtol=args.rtol, atol=args.atol,
                reference=dict(method=ref["method"], rtol=ref["rtol"], wall_s=ref["wall_s"], steps=ref["steps"]),
                rows=out_rows, machine=dict(platform=platform.platform(), cpus=os.cpu_count(),
                                            load_avg=os.getloadavg(), jax=jax.__version__),
                note="errors: max |end state - reference| over the rotor states and over all states")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(data, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
