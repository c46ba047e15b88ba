"""Scalars handed to compiled kernels."""
from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["strong"]


def strong(v: Any) -> Any:
    """A scalar as a strongly typed float array: a Python number, or a weakly typed array made from one, would
    give a compiled kernel an argument of another type (JAX's weak type) than the arrays of the computation, and
    the kernel would compile once more for it (the relocations of a special point compiled the residual anew,
    0.4 s each, because the fixed-lam row held weak zeros).  Anything else (strongly typed arrays, tracers, None,
    booleans) is returned as it is.

    A module that applies it in ``__init__`` (:class:`._collocation.Orbit`, :class:`._collocation.Constraint`)
    cannot serve as a ``jax.vmap`` ``in_axes`` spec (its integer axes would become floats); vmap over its arrays."""
    if isinstance(v, (bool, np.bool_)):
        return v
    if isinstance(v, (int, float, np.integer, np.floating)):
        return jnp.asarray(v, dtype=jnp.result_type(float))
    if isinstance(v, jax.Array) and not isinstance(v, jax.core.Tracer) and v.weak_type:
        # a weak integer (jnp.asarray(3)) becomes a float, as the Python int 3 does
        inexact = jnp.issubdtype(v.dtype, jnp.inexact)
        return jnp.asarray(v, dtype=v.dtype if inexact else jnp.result_type(float))
    return v
