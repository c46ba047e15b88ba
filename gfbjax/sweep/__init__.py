"""Parameter sweeps: many designs of one rotor-bearing system, each analysed the same way, run serially or on
dask.distributed, stored design by design and consolidated into an ``xarray.Dataset``.

    import gfbjax
    from gfbjax.sweep import run_sweep, Equilibria, Cycles

    ds = run_sweep(gfbjax.reference_system(Nx=24, Nz=3), grid={"alpha_f": [0.05, 0.1, 0.5], "eta": [0.05, 0.5]},
                   analyses=[Equilibria(0.05, 1.0), Cycles(0.05, 1.0, N=12)], out="results/sweep", workers=2)
    ds.hopf_omega_bar            # (alpha_f, eta): speed of the first Hopf point, NaN where there is none

Modules, one job each: :mod:`._designs` (grid or list of designs, checked), :mod:`._analyses` (the per-design
analyses and their figures), :mod:`._store` (one file per finished design, resume, the folder's identity),
:mod:`._execute` (the task of one design; serial and Dask execution), :mod:`._dataset` (the consolidated
Dataset), :mod:`.plot` (heat maps and line plots of the figures).

Where time goes: every design of a sweep has the same array shapes (grid, collocation mesh), so each process
compiles the kernels once and the persistent compilation cache lets the other processes load them.  On a CPU the
designs are best spread over processes (``workers``): XLA:CPU runs a vmapped batch of small dense LAPACK calls one
matrix after another, so batching designs into one vmapped kernel gains nothing there (see
:mod:`gfbjax.design.maps`); on an accelerator the vmapped batch wins.
"""

from ._analyses import ANALYSES, Analysis, Cycles, Energy, Equilibria, Figure, Optimum, Static, make_analyses
from ._designs import DesignSet, design_set
from ._execute import compute_design, local_cluster
from ._run import EXECUTORS, run_sweep
from ._store import SweepStore, design_key

__all__ = [
    "run_sweep",
    "EXECUTORS",
    "Analysis",
    "Figure",
    "Static",
    "Equilibria",
    "Cycles",
    "Energy",
    "Optimum",
    "ANALYSES",
    "make_analyses",
    "DesignSet",
    "design_set",
    "SweepStore",
    "design_key",
    "compute_design",
    "local_cluster",
]
