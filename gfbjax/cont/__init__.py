"""Generic numerical continuation (equilibria and periodic orbits) in JAX.

Knows nothing about bearings: works for any autonomous ``f(x, lam, args)``.
See ``collocation`` (periodic BVP, condensation of parameters), ``sparse_colloc``
(the same Newton system for large sparse fields: per-interval sparse LU, GMRES,
Arnoldi multipliers; chosen by ``CycleSettings.linear_solver``), ``sparsity``
(coloured Jacobians), ``floquet`` (stable product eigenvalues), ``palc`` (cycle
continuation), ``equilibria``, ``events`` and ``branch`` (results, npz + JSON storage).

XLA:CPU workaround: with jax/jaxlib 0.10 the compiled Newton kernel (scan +
LAPACK QR + small dots) can dead-lock at run time under XLA:CPU's
concurrency-optimised scheduler (observed for n=10, N>=30).  Importing this
package therefore appends ``--xla_cpu_enable_concurrency_optimized_scheduler=false``
to ``XLA_FLAGS`` unless the flag is already set.  This only takes effect if
the JAX backend has not been initialised yet (import ``gfbjax.cont`` before
running any JAX computation, or set the flag in the environment yourself).
For the same reason it sets ``NPROC`` (XLA:CPU's intra-op pool size) to max(8, cpu_count + 4) unless set: jaxlib's
batched LAPACK kernels block on sub-tasks in that pool and hang when as many of them run at once as it has threads
(two on a 2-core machine); see :mod:`gfbjax`.
"""
import os as _os

if "xla_cpu_enable_concurrency_optimized_scheduler" not in _os.environ.get("XLA_FLAGS", ""):
    _os.environ["XLA_FLAGS"] = (_os.environ.get("XLA_FLAGS", "")
                                + " --xla_cpu_enable_concurrency_optimized_scheduler=false").strip()
_os.environ.setdefault("NPROC", str(max(8, (_os.cpu_count() or 1) + 4)))

from .branch import Branch, PointRecord
from .collocation import (Constraint, NewtonResult, Orbit, Scheme, dense_newton_step, natural_constraint,
                          newton, newton_step, orbit_from_function, orbit_from_samples, palc_constraint,
                          transfer_matrices, uniform_mesh)
from .equilibria import EquilibriumSettings, HopfPoint, continue_equilibria, hopf_point
from .floquet import (PeriodicQRResult, multipliers_periodic, multipliers_product, nontrivial,
                      trivial_error)
from .palc import (CycleSettings, CycleStart, DenseBackend, analyse, continue_cycles, make_backend,
                   start_from_branch, start_from_function, start_from_hopf, start_from_pd, start_from_samples)
from .sparse_colloc import SparseCollocation
from .sparsity import Coloring, color_pattern, jacobian_values
from .problem import CycleProblem, EquilibriumProblem

__all__ = [
    "Branch", "PointRecord", "Constraint", "NewtonResult", "Orbit", "Scheme", "dense_newton_step",
    "natural_constraint", "newton", "newton_step", "orbit_from_function", "orbit_from_samples",
    "palc_constraint", "transfer_matrices", "uniform_mesh", "EquilibriumSettings", "HopfPoint",
    "continue_equilibria", "hopf_point", "PeriodicQRResult", "multipliers_periodic",
    "multipliers_product", "nontrivial", "trivial_error", "CycleSettings", "CycleStart", "analyse",
    "continue_cycles", "start_from_branch", "start_from_function", "start_from_hopf", "start_from_pd",
    "start_from_samples", "CycleProblem", "EquilibriumProblem", "DenseBackend", "make_backend",
    "SparseCollocation", "Coloring", "color_pattern", "jacobian_values",
]
