"""Process-wide settings that gfbjax needs from XLA:CPU and OpenBLAS, in one place.

They are environment variables read once, when the library that uses them starts (the JAX backend, an OpenBLAS
library), so they must be set before that.  :func:`configure_process` sets each one only where the user has not set
it, and warns (:class:`RuntimeWarning`) when it comes too late to take effect:

* ``XLA_FLAGS += --xla_cpu_enable_concurrency_optimized_scheduler=false``: the compiled collocation Newton step
  dead-locks under XLA:CPU's concurrency-optimised scheduler (seen for n = 10, N >= 30 intervals, jax 0.10).
* ``NPROC = max(8, cpu_count + 4)``, the size of XLA:CPU's intra-op thread pool.  jaxlib's batched LAPACK kernels
  (LU, triangular solve) split their batch over that pool and block until the pieces finish; when as many of them
  run concurrently as the pool has threads, none of the pieces can run and the process hangs at 0% CPU.  With the
  default pool of one thread per core a 2-core machine hangs on two concurrent kernels (reproduced with four
  independent vmapped triangular solves, tests/test_xla_threads.py; also seen in the batched maps and the gradient
  kernels).  Extra threads only wait, so the larger pool costs nothing measurable.
* ``OPENBLAS_NUM_THREADS = 1``: several BLAS threads on a busy 2-core machine slowed the small dense QR/LU
  factorisations of the solvers ~100-1000x.  OpenBLAS reads it when it is loaded: numpy's copy when numpy is
  imported, scipy's (the LAPACK that jaxlib calls on the CPU) when ``scipy.linalg`` is first imported, usually by
  JAX's first LAPACK kernel.

``OMP_NUM_THREADS`` is not set: OpenBLAS reads ``OPENBLAS_NUM_THREADS`` first (``OMP_NUM_THREADS`` only when that
is unset), the OpenBLAS builds of the numpy and scipy wheels use their own threads, not OpenMP, and XLA:CPU does not
use OpenMP either, so it would change nothing for gfbjax and only the importer's other libraries.

Who calls it: ``import gfbjax`` does (the deadlock is real and silent), which changes only variables the user has
not set and warns once, naming them, when the JAX backend was already running (then the flags cannot take effect:
restart the process and import gfbjax, or set the variables, before the first JAX computation).  At import it
does not warn about OpenBLAS: importing numpy before gfbjax is the normal order, and scipy's copy, the one the
solvers use, is usually loaded later.  The command line (:func:`gfbjax.cli.main`) calls it explicitly.  To keep
a process entirely as it is, set the variables yourself before importing gfbjax (any value counts as set; for
``XLA_FLAGS``, any value of the scheduler flag).
"""

from __future__ import annotations

import os
import sys
import tempfile
import warnings

__all__ = [
    "configure_process",
    "process_defaults",
    "jax_backend_initialized",
    "compilation_cache_dir",
    "enable_compilation_cache",
]

_SCHEDULER_FLAG = "xla_cpu_enable_concurrency_optimized_scheduler"
_warned: set[str] = set()


def process_defaults() -> dict[str, str]:
    """The values gfbjax wants (``XLA_FLAGS`` as the flag to append), whatever the environment holds now."""
    return {
        "XLA_FLAGS": f"--{_SCHEDULER_FLAG}=false",
        "NPROC": str(max(8, (os.cpu_count() or 1) + 4)),
        "OPENBLAS_NUM_THREADS": "1",
    }


def _user_set(name: str) -> bool:
    """Whether the environment already decides ``name`` (for XLA_FLAGS: the scheduler flag is present)."""
    if name == "XLA_FLAGS":
        return _SCHEDULER_FLAG in os.environ.get("XLA_FLAGS", "")
    return name in os.environ


def jax_backend_initialized() -> bool:
    """Whether a JAX backend has started in this process (then XLA_FLAGS and NPROC are read already).

    jax has no public test for this (0.10); ``jax._src.xla_bridge.backends_are_initialized`` is used where it
    exists, else the backend cache ``_backends``; False when neither is there or jax is not imported.
    """
    if "jax" not in sys.modules:
        return False
    try:
        from jax._src import xla_bridge
    except ImportError:  # pragma: no cover - a future jax without this module
        return False
    test = getattr(xla_bridge, "backends_are_initialized", None)
    if callable(test):
        return bool(test())
    return bool(getattr(xla_bridge, "_backends", None))


def _blas_loaded() -> list[str]:
    """The imported modules whose OpenBLAS has read its thread count already."""
    return [m for m in ("numpy", "scipy.linalg") if m in sys.modules]


def configure_process(*, warn_blas: bool = True) -> dict[str, str]:
    """Set gfbjax's process defaults (module docstring) where the user has not set them.

    Warns with a :class:`RuntimeWarning`, once per variable and process, when a variable it had to set cannot take
    effect any more: ``XLA_FLAGS``/``NPROC`` after the JAX backend started, ``OPENBLAS_NUM_THREADS`` (only with
    ``warn_blas``) after numpy or ``scipy.linalg`` was imported.

    Returns:
        The variables it set, with their new values (empty when the environment already decided all of them).
    """
    changed: dict[str, str] = {}
    for name, value in process_defaults().items():
        if _user_set(name):
            continue
        new = f"{os.environ.get(name, '')} {value}".strip() if name == "XLA_FLAGS" else value
        os.environ[name] = new
        changed[name] = new
    late_xla = [n for n in ("XLA_FLAGS", "NPROC") if n in changed] if jax_backend_initialized() else []
    if late_xla:
        _warn(late_xla, "the JAX backend is already initialised, so XLA:CPU has read its settings: the "
                        "concurrency-optimised scheduler and the intra-op pool that can dead-lock batched LAPACK "
                        "kernels on small machines stay in effect")
    blas = _blas_loaded() if warn_blas and "OPENBLAS_NUM_THREADS" in changed else []
    if blas:
        _warn(["OPENBLAS_NUM_THREADS"], f"{' and '.join(blas)} already loaded OpenBLAS with its default thread "
                                        "count, which can make the solvers' small factorisations much slower")
    return changed


def _warn(names: list[str], why: str) -> None:
    names = [n for n in names if n not in _warned]
    if not names:
        return
    _warned.update(names)
    values = process_defaults()
    setting = ", ".join(f"{n}={values[n]}" for n in names)
    warnings.warn(f"gfbjax could not apply {setting}: {why}.  Import gfbjax before running any JAX computation, or "
                  f"set these variables before starting Python (see gfbjax._process).", RuntimeWarning, stacklevel=3)


CACHE_ENV = "GFBJAX_CACHE_DIR"


def compilation_cache_dir() -> str | None:
    """The folder of JAX's persistent compilation cache that gfbjax programs use, or None when it is switched off.

    ``$GFBJAX_CACHE_DIR`` when set (the values ``""``, ``0``, ``off`` and ``none`` switch the cache off), else
    ``$XDG_CACHE_HOME/gfbjax/jax`` (``~/.cache/gfbjax/jax`` by default).
    """
    value = os.environ.get(CACHE_ENV)
    if value is not None:
        return None if value.strip().lower() in ("", "0", "off", "none", "false") else os.path.expanduser(value)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "gfbjax", "jax")


def enable_compilation_cache(path: str | None = None) -> str | None:
    """Turn on JAX's persistent compilation cache in ``path`` (default :func:`compilation_cache_dir`).

    Why: a continuation compiles a handful of large kernels (the collocation Newton step, the Floquet sweeps) that
    take 30-60 s on a small machine, the same for every run with the same grid; with the cache a second run loads
    them in a few seconds.  Every kernel is cached, however quick its compilation (JAX's default keeps only those
    above one second).  The CLI, :mod:`gfbjax.sweep` and its Dask workers call this; a library user may too.
    The cache is keyed by the program, shapes, jax version and device, so a stale entry is never used.

    Returns:
        The folder in use, or None when the cache is switched off (``GFBJAX_CACHE_DIR=off``) or cannot be created
        (then a :class:`RuntimeWarning` says why and everything still runs, only compiling again).
    """
    folder = compilation_cache_dir() if path is None else os.path.expanduser(path)
    if folder is None:
        return None
    try:
        os.makedirs(folder, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):  # an existing folder may still refuse writes
            pass
    except OSError as exc:
        warnings.warn(f"gfbjax: compilation cache disabled, cannot write to {folder!r} ({exc}); set "
                      f"{CACHE_ENV} to a writable folder, or to 'off'", RuntimeWarning, stacklevel=2)
        return None
    import jax

    jax.config.update("jax_compilation_cache_dir", folder)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return folder
