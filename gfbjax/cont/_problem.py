"""Problem definitions (what is continued), kept apart from settings and results.

A problem is an autonomous vector field ``f(x, lam, args) -> dx/dt`` with
``x`` a 1-D float64 array of length ``n``, ``lam`` the scalar continuation
parameter and ``args`` any pytree of fixed parameters (e.g. an
``equinox.Module``).  ``f`` must be a pure JAX function; it is treated as a
static (hashable) object by ``jax.jit`` so keep the same function object for a
whole continuation to avoid re-compilation.
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

import jax
import numpy as np


def _is_int(v: Any) -> bool:
    return isinstance(v, numbers.Integral) and not isinstance(v, (bool, np.bool_))


def _check_common(problem: Any) -> None:
    f, n, record = problem.f, problem.n, problem.record
    if not callable(f):
        raise ValueError(f"f must be callable f(x, lam, args), got {type(f).__name__}")
    if not (_is_int(n) and n >= 1):
        raise ValueError(f"n (state dimension) must be an int >= 1, got {n!r}")
    object.__setattr__(problem, "n", int(n))  # numpy integers are welcome; store a Python int
    if record is not None:
        bad = [c for c in record if not (_is_int(c) and 0 <= c < n)]
        if bad:
            raise ValueError(f"record must hold component indices in [0, {n}), got {bad}")


@dataclass(frozen=True)
class CycleProblem:
    """Periodic orbits of ``x' = f(x, lam, args)``.

    n_trivial: number of Floquet multipliers that are 1 by construction
    (1 for an autonomous system; more with symmetries / first integrals /
    autonomous forcing oscillators).  record: state components whose max/min
    over the cycle are stored (None: all).  jac_sparsity: optional boolean
    (n, n) pattern of df/dx (True where an entry may be non-zero); with it,
    large problems can use the sparse linear solver (``SparseSweep``).
    """

    f: Callable[[jax.Array, jax.Array, Any], jax.Array]
    n: int
    args: Any = None
    n_trivial: int = 1
    record: Sequence[int] | None = None
    jac_sparsity: Any = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        _check_common(self)
        if not (isinstance(self.n_trivial, int) and 1 <= self.n_trivial <= self.n):
            raise ValueError(f"n_trivial must be an int in [1, n={self.n}], got {self.n_trivial!r}")
        if self.jac_sparsity is not None and np.shape(self.jac_sparsity) != (self.n, self.n):
            raise ValueError(f"jac_sparsity must have shape (n, n) = ({self.n}, {self.n}), "
                             f"got {np.shape(self.jac_sparsity)}")

    @property
    def components(self) -> list[int]:
        return list(range(self.n)) if self.record is None else [int(c) for c in self.record]


@dataclass(frozen=True)
class EquilibriumProblem:
    """Equilibria ``f(x, lam, args) = 0``."""

    f: Callable[[jax.Array, jax.Array, Any], jax.Array]
    n: int
    args: Any = None
    record: Sequence[int] | None = None

    def __post_init__(self) -> None:
        _check_common(self)

    @property
    def components(self) -> list[int]:
        return list(range(self.n)) if self.record is None else [int(c) for c in self.record]


def check_range(name: str, value: Any, lo: float, hi: float, *, lo_open: bool = False,
                hi_open: bool = False, integer: bool = False) -> None:
    """Raise ``ValueError`` naming the field unless lo <= value <= hi (open ends optional).  Python and NumPy
    numbers are accepted (booleans are not); ``integer`` also refuses 16.0."""
    ok_type = isinstance(value, numbers.Integral if integer else numbers.Real) and not isinstance(
        value, (bool, np.bool_))
    ok = ok_type and (value > lo if lo_open else value >= lo) and (value < hi if hi_open else value <= hi)
    if not ok:
        rng = f"{'(' if lo_open else '['}{lo}, {hi}{')' if hi_open else ']'}"
        kind = "an int" if integer else "a number"
        raise ValueError(f"{name} must be {kind} in {rng}, got {value!r}")
