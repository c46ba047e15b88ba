"""Regression test for the XLA:CPU hang that importing gfbjax works around (``NPROC``, see :mod:`gfbjax`).

jaxlib's batched LAPACK kernels split their batch over XLA:CPU's intra-op pool and block until the pieces finish;
when as many such kernels run at once as the pool has threads, the process hangs at 0% CPU.  The kernel below
(four independent vmapped triangular solves and a batched LU solve, each above jaxlib's parallel-work threshold)
hung in 3 of 3 runs within its first two calls on the 2-core development machine with the default pool and XLA's
default scheduler; with the pool gfbjax sets it finishes in about a second.  (gfbjax also turns that scheduler off,
which hides this small kernel's hang but not the hangs seen in the batched maps and the gradient kernels.)  It runs in a subprocess so that a hang fails the test (timeout)
instead of stalling the session.
"""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

KERNEL = """
import gfbjax, os
import jax, jax.numpy as jnp
from jax.scipy.linalg import solve_triangular
assert int(os.environ["NPROC"]) >= 8, os.environ["NPROC"]

@jax.jit
def f(R, B):
    s = jax.vmap(lambda r, b: solve_triangular(r, b, lower=False))
    L = jax.vmap(jnp.linalg.solve)(R + jnp.eye(R.shape[-1]), B)
    return sum(s(R, B * (i + 1.0)) for i in range(4)) + L

key = jax.random.PRNGKey(0)
R = jnp.triu(jax.random.normal(key, (64, 120, 120))) + 10 * jnp.eye(120)
B = jax.random.normal(key, (64, 120, 40))
for _ in range(5):
    jax.block_until_ready(f(R, B))
print("done")
"""


def test_concurrent_batched_lapack_does_not_hang():
    env = {k: v for k, v in os.environ.items() if k != "NPROC"}  # the default gfbjax sets, not the caller's
    # XLA's concurrency-optimised scheduler (which gfbjax otherwise turns off) makes this small kernel hang reliably
    # with the default pool; the pool size alone must prevent it.
    env["XLA_FLAGS"] = "--xla_cpu_enable_concurrency_optimized_scheduler=true"
    try:
        r = subprocess.run([sys.executable, "-c", KERNEL], env=env, capture_output=True, text=True, timeout=180)
    except subprocess.TimeoutExpired:
        pytest.fail("concurrent batched LAPACK kernels hung (XLA:CPU intra-op pool too small)")
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip().endswith("done")
