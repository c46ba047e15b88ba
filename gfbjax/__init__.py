"""gfbjax: nonlinear dynamics of rotors on gas foil bearings in JAX.

Importing gfbjax turns on JAX's 64-bit mode: Newton corrections, Floquet multipliers that span many decades and
finite-difference checks of gradients all need double precision.

Three process-wide defaults are set at import, before any JAX computation, and only where the user has not set
them (they take effect only if the JAX backend was not initialised before gfbjax was imported):

* ``XLA_FLAGS += --xla_cpu_enable_concurrency_optimized_scheduler=false``: the compiled collocation Newton step
  dead-locks under XLA:CPU's concurrency-optimised scheduler (seen for n = 10, N >= 30 intervals).
* ``NPROC = max(8, cpu_count + 4)``, the size of XLA:CPU's intra-op thread pool.  jaxlib's batched LAPACK kernels
  (LU, triangular solve) split their batch over that pool and block until the pieces finish; when as many of them
  run concurrently as the pool has threads, none of the pieces can run and the process hangs at 0% CPU.  With the
  default pool of one thread per core a 2-core machine hangs on two concurrent kernels (reproduced with four
  independent vmapped triangular solves; also seen in the batched maps and the gradient kernels).  Extra threads
  only wait, so the larger pool costs nothing measurable (benchmarks in the session notes).
* ``OPENBLAS_NUM_THREADS=1``: several BLAS threads on a busy 2-core machine slowed the small dense QR/LU
  factorisations of the solvers ~100-1000x; it takes effect only if numpy was not imported before gfbjax.
"""

import os as _os

if "xla_cpu_enable_concurrency_optimized_scheduler" not in _os.environ.get("XLA_FLAGS", ""):
    _os.environ["XLA_FLAGS"] = (_os.environ.get("XLA_FLAGS", "")
                                + " --xla_cpu_enable_concurrency_optimized_scheduler=false").strip()
_os.environ.setdefault("NPROC", str(max(8, (_os.cpu_count() or 1) + 4)))
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from .params import (  # noqa: E402
    VARIATIONS,
    ParameterError,
    Params,
    SystemSpec,
    bump_foil_compliance,
    load_config,
    reference_system,
    system_from_name_or_file,
    unbalance_eccentricity,
    validation_case,
    variation,
)

__all__ = [
    "VARIATIONS",
    "ParameterError",
    "Params",
    "SystemSpec",
    "bump_foil_compliance",
    "load_config",
    "reference_system",
    "system_from_name_or_file",
    "unbalance_eccentricity",
    "validation_case",
    "variation",
]
__version__ = "0.1.0"
