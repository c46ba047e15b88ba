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

from ._checks import check_flag, check_range, store


@dataclass(frozen=True)
class Monitor:
    """A physical bound watched along a branch: ``fn(x, lam, args)`` (a scalar, pure JAX) must stay above
    ``minimum`` at every state of every point (cycles: at every collocation node of the orbit).

    Why: a branch can be a perfectly converged solution of the equations and still be outside the model's
    validity, e.g. a bearing cycle whose gas film closes (h_min <= 0), where the Reynolds equation no longer holds.
    ``stop=True``: the branch ends where the bound is crossed (the crossing is located and recorded as its last
    point; outcome ``CONTACT``).  ``stop=False``: it goes on, and the points below the bound are flagged
    (:attr:`Branch.flagged`).  Each point's value is kept in ``Branch.monitor``.  ``name`` and ``unit`` describe
    it in results and messages.
    """

    name: str
    fn: Callable[[jax.Array, jax.Array, Any], jax.Array] = field(compare=False)
    minimum: float
    stop: bool = True
    unit: str = ""

    def __post_init__(self) -> None:
        if not callable(self.fn):
            raise ValueError(f"Monitor.fn must be callable fn(x, lam, args), got {type(self.fn).__name__}")
        store(self, "minimum", check_range("Monitor.minimum", self.minimum, -np.inf, np.inf, lo_open=True,
                                           hi_open=True))
        store(self, "stop", check_flag("Monitor.stop", self.stop))
        for name in ("name", "unit"):
            if not isinstance(getattr(self, name), str):
                raise ValueError(f"Monitor.{name} must be a string, got {getattr(self, name)!r}")


    def describe(self) -> dict[str, Any]:
        """What a branch records about its monitor (``Branch.monitor_info``, JSON-able)."""
        return {"name": self.name, "minimum": float(self.minimum), "unit": self.unit, "stop": bool(self.stop)}


def _check_monitor(problem: Any) -> None:
    if problem.monitor is not None and not isinstance(problem.monitor, Monitor):
        raise ValueError(f"monitor must be a Monitor or None, got {type(problem.monitor).__name__}")


def _check_common(problem: Any) -> None:
    f, n, record = problem.f, problem.n, problem.record
    if not callable(f):
        raise ValueError(f"f must be callable f(x, lam, args), got {type(f).__name__}")
    n = check_range("n (state dimension)", n, 1, 10**9, integer=True)
    store(problem, "n", n)
    if record is not None:
        bad = [c for c in record if not (isinstance(c, numbers.Integral) and not isinstance(c, (bool, np.bool_))
                                         and 0 <= c < n)]
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
    large problems can use the sparse linear solver (``SparseSweep``).  monitor: an optional physical bound
    watched at every point (:class:`Monitor`).
    """

    f: Callable[[jax.Array, jax.Array, Any], jax.Array]
    n: int
    args: Any = None
    n_trivial: int = 1
    record: Sequence[int] | None = None
    jac_sparsity: Any = field(default=None, compare=False, repr=False)
    monitor: Monitor | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        _check_common(self)
        _check_monitor(self)
        store(self, "n_trivial", check_range("n_trivial", self.n_trivial, 1, self.n, integer=True))
        if self.jac_sparsity is not None and np.shape(self.jac_sparsity) != (self.n, self.n):
            raise ValueError(f"jac_sparsity must have shape (n, n) = ({self.n}, {self.n}), "
                             f"got {np.shape(self.jac_sparsity)}")

    @property
    def components(self) -> list[int]:
        return list(range(self.n)) if self.record is None else [int(c) for c in self.record]


@dataclass(frozen=True)
class EquilibriumProblem:
    """Equilibria ``f(x, lam, args) = 0``; ``monitor``: an optional physical bound (:class:`Monitor`)."""

    f: Callable[[jax.Array, jax.Array, Any], jax.Array]
    n: int
    args: Any = None
    record: Sequence[int] | None = None
    monitor: Monitor | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        _check_common(self)
        _check_monitor(self)

    @property
    def components(self) -> list[int]:
        return list(range(self.n)) if self.record is None else [int(c) for c in self.record]
