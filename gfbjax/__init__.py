"""gfbjax: nonlinear dynamics of rotors on gas foil bearings in JAX.

Importing gfbjax does two things to the process, both documented where they are done:

* it turns on JAX's 64-bit mode (``jax_enable_x64``): Newton corrections, Floquet multipliers that span many decades
  and finite-difference checks of gradients all need double precision, and every solver assumes float64;
* it calls :func:`gfbjax._process.configure_process`, which works around an XLA:CPU dead-lock of jaxlib's batched
  LAPACK kernels (``XLA_FLAGS``, ``NPROC``) and slow multi-threaded BLAS on small machines
  (``OPENBLAS_NUM_THREADS``), setting only the variables the user has not set, and warning when JAX was already
  running (then they cannot take effect).  See that module for why and how to opt out.

The allowed ranges of all inputs are in :mod:`gfbjax.limits`.
"""

from ._process import configure_process as _configure_process

# warn_blas=False: importing numpy first is the normal order (see gfbjax._process); JAX started first is not.
_configure_process(warn_blas=False)

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from . import limits  # noqa: E402
from .limits import NoSolutionError  # noqa: E402
from .params import (  # noqa: E402
    PRESETS,
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
    "limits",
    "NoSolutionError",
    "PRESETS",
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
