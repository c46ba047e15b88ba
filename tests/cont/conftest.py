import os
import sys

# XLA:CPU dead-lock workaround (see gfbjax/cont/__init__.py); must precede backend init.
if "xla_cpu_enable_concurrency_optimized_scheduler" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "")
                               + " --xla_cpu_enable_concurrency_optimized_scheduler=false").strip()

# OpenBLAS (used by numpy/scipy and by JAX's CPU LAPACK calls) with several
# threads on a small, shared machine slows small QRs by ~1000x; tests use one thread.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
sys.path.insert(0, os.path.dirname(__file__))
