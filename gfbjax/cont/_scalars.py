"""Scalars handed to compiled kernels."""
from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

__all__ = ["strong", "float_array"]


def strong(v: Any) -> Any:
    """A real scalar as a strongly typed array of the computation's float type (float64 with gfbjax's x64).

    A Python number, or a weakly typed array made from one (JAX's weak type), gives a compiled kernel an argument
    of another type than the arrays of the computation, and the kernel compiles once more for it: the relocations
    of a special point compiled the residual anew, 0.4 s each, because the fixed-lam row held weak zeros.  A 0-d
    array of another real dtype (``np.array(3)`` as ``np.load`` gives it, ``jnp.float32``) is cast too: the
    corrector's loop carries the float type and refuses another.  Anything else (float arrays of that type, arrays
    of higher rank, tracers, None, booleans, complex numbers) is returned as it is.

    A module that applies it in ``__init__`` (:class:`._collocation.Orbit`, :class:`._collocation.Constraint`)
    cannot serve as a ``jax.vmap`` ``in_axes`` spec (its integer axes would become floats); vmap over its arrays."""
    if isinstance(v, (bool, np.bool_)) or v is None or isinstance(v, jax.core.Tracer):
        return v
    if isinstance(v, (int, float, np.integer, np.floating)):
        return jnp.asarray(v, dtype=jnp.result_type(float))
    if isinstance(v, (np.ndarray, jax.Array)) and v.ndim == 0:
        # any real 0-d array (np.array(3) as np.load gives it, jnp.int32, jnp.float32, a weak array) becomes the
        # float of the computation: the corrector's loop carries that type and refuses another
        return float_array(v)
    return v


def float_array(v: Any) -> Any:
    """An array of the computation's float type from a list, a tuple or an array of another real dtype (float32,
    integers): the corrector's loop carries that type and refuses another (a float32 ``xm`` failed deep inside
    JAX's while loop with a message about its carry).  Arrays of that type, tracers and anything else (None,
    placeholders of tree utilities) are returned as they are."""
    if isinstance(v, jax.core.Tracer):
        return v
    if isinstance(v, (list, tuple)):
        return jnp.asarray(v, dtype=jnp.result_type(float))
    if isinstance(v, (np.ndarray, jax.Array)) and (jnp.issubdtype(v.dtype, jnp.integer)
                                                   or jnp.issubdtype(v.dtype, jnp.floating)):
        dtype = jnp.result_type(float)
        if v.dtype != dtype or getattr(v, "weak_type", False):
            return jnp.asarray(v, dtype=dtype)
    return v
