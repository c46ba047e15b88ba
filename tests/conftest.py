"""Test-session set-up: gfbjax's process defaults (x64, XLA scheduler flag, single-threaded BLAS) before any
JAX computation.  Importing gfbjax sets them."""
import gc

import jax
import pytest

import gfbjax  # noqa: F401


@pytest.fixture(autouse=True, scope="module")
def _release_compiled_code():
    """Drop the compiled executables of each test module before the next one.

    Every XLA:CPU executable keeps memory mappings of its own, and the kernel caps them per process
    (vm.max_map_count, 65530 by default).  The whole suite in one process compiles enough to pass that cap: the
    count reached 35,000 by a tenth of the suite, and XLA then crashed while compiling (a segmentation fault or an
    abort; two CI runs on 2026-11-30).  Kernels a later module needs again come back from the compilation cache."""
    yield
    jax.clear_caches()
    gc.collect()
