"""gfbjax: nonlinear dynamics of rotors on gas foil bearings in JAX.

Importing gfbjax turns on JAX's 64-bit mode: Newton corrections, Floquet multipliers that span many decades and
finite-difference checks of gradients all need double precision.
"""

import jax

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
