"""Sparse Jacobians by column colouring (Curtis-Powell-Reid), for vector fields with a known sparsity pattern.

A Jacobian ``J = df/dx`` whose pattern is known can be recovered from far fewer than ``n`` directional
derivatives: columns that share no row are given the same colour and probed by one JVP with the sum of their unit
vectors.  A few *dense rows* (e.g. a rotor acceleration that integrates every film pressure) would force every
column into its own colour; they are taken out of the colouring and obtained by reverse mode, one VJP each.

The result is a :class:`Coloring` built once per pattern, and :func:`jacobian_values`, which returns the Jacobian's
values at the pattern's entries (row-major order, diagonal always included) from ``n_colors`` JVPs and
``len(dense_rows)`` VJPs.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np


@dataclass(frozen=True, eq=False)
class Coloring:
    """Column colouring of a sparsity pattern.

    rows, cols: the structural entries (pattern plus diagonal), row-major; color: colour of each column;
    dense_rows: rows taken by VJP.  Compared and hashed by identity, so that one colouring can be a static
    argument of compiled code (make it once per pattern and keep it).
    """

    n: int
    rows: np.ndarray
    cols: np.ndarray
    color: np.ndarray
    n_colors: int
    dense_rows: np.ndarray

    @property
    def nnz(self) -> int:
        return int(self.rows.size)

    def seeds(self) -> np.ndarray:
        """(n, n_colors) JVP seed matrix."""
        S = np.zeros((self.n, self.n_colors))
        S[np.arange(self.n), self.color] = 1.0
        return S

    def is_dense_entry(self) -> np.ndarray:
        return np.isin(self.rows, self.dense_rows)

    def dense_row_position(self) -> np.ndarray:
        """For each entry, the index of its row among ``dense_rows`` (0 where the row is sparse)."""
        pos = np.zeros(self.n, dtype=int)
        pos[self.dense_rows] = np.arange(self.dense_rows.size)
        return pos[self.rows]


def color_pattern(pattern: np.ndarray, dense_threshold: int | None = None) -> Coloring:
    """Greedy column colouring of a boolean (n, n) pattern (largest columns first).

    Rows with more than ``dense_threshold`` entries (default ``max(16, n // 4)``) are dense rows.
    """
    pat = np.asarray(pattern, dtype=bool)
    n = pat.shape[0]
    if pat.shape != (n, n):
        raise ValueError(f"pattern must be square (n, n), got shape {pat.shape}")
    pat = pat | np.eye(n, dtype=bool)
    thr = max(16, n // 4) if dense_threshold is None else int(dense_threshold)
    dense_rows = np.where(pat.sum(axis=1) > thr)[0]
    sp = pat.copy()
    sp[dense_rows] = False
    color = -np.ones(n, dtype=int)
    used: list[np.ndarray] = []
    for c in np.argsort(-sp.sum(axis=0), kind="stable"):
        col = sp[:, c]
        for k, u in enumerate(used):
            if not (u & col).any():
                color[c] = k
                u |= col
                break
        else:
            color[c] = len(used)
            used.append(col.copy())
    rows, cols = np.nonzero(pat)
    return Coloring(n=n, rows=rows, cols=cols, color=color, n_colors=len(used), dense_rows=dense_rows)


def dense_jacobian(fn: Callable[[jax.Array], jax.Array], x: jax.Array, coloring: Coloring) -> jax.Array:
    """The (n, n) Jacobian of ``fn`` at ``x`` from :func:`jacobian_values` (for dense factorisations)."""
    c = coloring
    return jnp.zeros((c.n, c.n), x.dtype).at[c.rows, c.cols].set(jacobian_values(fn, x, c))


def jacobian_values(fn: Callable[[jax.Array], jax.Array], x: jax.Array, coloring: Coloring) -> jax.Array:
    """Values of ``d fn / dx`` at ``coloring``'s entries (``coloring.nnz``,): JVPs per colour, VJPs per dense row."""
    c = coloring
    S = jnp.asarray(c.seeds(), dtype=x.dtype)
    JS = jax.vmap(lambda v: jax.jvp(fn, (x,), (v,))[1], in_axes=1, out_axes=1)(S)  # (n, n_colors)
    vals = JS[c.rows, c.color[c.cols]]
    if c.dense_rows.size:
        _, vjp = jax.vjp(fn, x)
        E = jnp.zeros((c.dense_rows.size, c.n), x.dtype).at[np.arange(c.dense_rows.size), c.dense_rows].set(1.0)
        JD = jax.vmap(lambda e: vjp(e)[0])(E)  # (n_dense, n)
        vals = jnp.where(jnp.asarray(c.is_dense_entry()), JD[c.dense_row_position(), c.cols], vals)
    return vals


@partial(jax.jit, static_argnums=(0, 4))
def _probe(f, x, lam, args, coloring, v):
    """J v exactly and the Jacobian's values at the pattern's entries, for f(x, lam, args) at x."""
    fn = lambda y: f(y, lam, args)
    return jax.jvp(fn, (x,), (v,))[1], jacobian_values(fn, x, coloring)


def check_pattern(f: Callable, x: jax.Array, lam: jax.Array, args, coloring: Coloring, name: str = "jac_sparsity",
                  seed: int = 0) -> None:
    """Raise ``ValueError`` when the pattern behind ``coloring`` misses non-zero entries of ``df/dx`` of
    ``f(x, lam, args)`` at ``x`` (shape (n,)).

    A missing entry is not an error the colouring can see: its derivative is added to another entry of the same
    colour, or dropped, and every Jacobian built from the pattern is silently wrong (Newton still converges, on
    the exact residual, but the tangent, the multipliers and the stability are wrong).  The test: one directional
    derivative J v along a random v against the pattern's J v, equal to rounding when the pattern holds every
    non-zero entry at ``x`` (one compiled kernel per f and pattern).  On failure the entries outside the pattern
    are read off the full Jacobian (``n`` JVPs, only then) and the first few named."""
    c = coloring
    v = np.random.default_rng(seed).standard_normal(c.n)
    exact, vals = (np.asarray(a) for a in _probe(f, jnp.asarray(x), jnp.asarray(lam), args, c, jnp.asarray(v)))
    patterned, scale = np.zeros(c.n), np.zeros(c.n)
    np.add.at(patterned, c.rows, vals * v[c.cols])
    np.add.at(scale, c.rows, np.abs(vals * v[c.cols]))
    gap = np.abs(exact - patterned)
    judged = np.isfinite(gap)  # a row whose derivative is not finite at x (a kink, sqrt at 0) says nothing here
    # rounding: relative to each row's terms, and to the largest entry for rows whose terms cancel
    top = np.max(np.abs(exact[judged]), initial=0.0)
    if np.all(gap[judged] <= 1e-8 * (np.abs(exact[judged]) + scale[judged]) + 1e-12 * top):
        return
    J = np.asarray(jax.jacfwd(lambda y: f(y, lam, args))(jnp.asarray(x)))
    inside = np.zeros((c.n, c.n), bool)
    inside[c.rows, c.cols] = True
    outside = np.argwhere(~inside & (np.abs(J) > 1e-12 * np.max(np.abs(J))))
    listed = ", ".join(f"({i}, {j}) = {J[i, j]:.3g}" for i, j in outside[:5])
    what = (f"leaves out non-zero entries of df/dx (row, column): {listed}{' and more' if len(outside) > 5 else ''} "
            f"({len(outside)} in all)" if len(outside) else
            f"does not reproduce df/dx: J v differs by up to {np.max(gap[judged]):.3g} from the pattern's J v")
    raise ValueError(f"{name} {what}, at a state of the first orbit; a Jacobian built from the pattern would be "
                     "wrong (and with it the multipliers and stability): mark every entry that can be non-zero as "
                     "True")
