"""Stable product-eigenvalue method vs the plain product on multipliers spanning ~1e-30..1."""
import jax
import jax.numpy as jnp
import numpy as np
from math import factorial

from gfbjax.cont import _collocation as col
from gfbjax.cont import _floquet as floquet
from cont_systems import correct


def test_periodic_qr_on_random_product_with_known_eigenvalues():
    """G_j = S D_j S^{-1} (S random, well conditioned): eigenvalues of the
    product are prod_j D_j exactly; they span 1e0 .. 1e-40."""
    rng = np.random.default_rng(1)
    n, N = 6, 20
    S = np.eye(n) + 0.3 * rng.normal(size=(n, n))
    Si = np.linalg.inv(S)
    logs = -np.array([0.0, 2.0, 7.0, 15.0, 25.0, 40.0]) * np.log(10) / N
    G = np.array([S @ np.diag(np.exp(logs) * (1 + 0.01 * rng.normal(size=n))) @ Si for _ in range(N)])
    exact = np.prod([np.diag(Si @ g @ S) for g in G], axis=0)
    exact = exact[np.argsort(-np.abs(exact))]
    res = floquet.multipliers_periodic(G)
    assert res.converged
    rel = np.abs(res.multipliers.real / exact - 1)
    assert np.max(rel) < 1e-8, rel
    plain = floquet.multipliers_product(G)
    plain = plain[np.argsort(-np.abs(plain))]
    assert np.abs(plain[-1] / exact[-1] - 1) > 1.0   # the plain product loses the 1e-40 one


def test_periodic_qr_complex_pair():
    """Rotation blocks (complex multipliers of equal modulus) are handled as 2x2 blocks."""
    th, N = 0.3, 10
    R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    G = np.zeros((N, 3, 3))
    G[:, :2, :2] = 0.9 * R
    G[:, 2, 2] = 1e-3
    mu = floquet.multipliers_periodic(G).multipliers
    assert np.allclose(np.sort_complex(mu[:2]), np.sort_complex(0.9 ** N * np.exp([-1j * N * th, 1j * N * th])),
                       rtol=1e-12)
    assert abs(mu[2] / 1e-30 - 1) < 1e-10


def _pade(z, m):
    """(m,m) Pade approximant of exp(z) = stability function of m-stage Gauss collocation."""
    c = [factorial(2 * m - k) * factorial(m) / (factorial(2 * m) * factorial(k) * factorial(m - k))
         for k in range(m + 1)]
    P = lambda x: sum(ck * x ** k for k, ck in enumerate(c))
    return P(z) / P(-z)


W, LAM, NZ = 2.0, 0.5, 8
RATES_T = -np.linspace(1.0, 69.0, NZ)          # lambda_k T in [-69, -1]: multipliers down to 1e-30


def stiff_field(x, lam, A):
    r2 = x[0] ** 2 + x[1] ** 2
    return jnp.concatenate([jnp.array([lam * x[0] - W * x[1] - x[0] * r2, W * x[0] + lam * x[1] - x[1] * r2]),
                            A @ x[2:]])


def test_stable_floquet_on_stiff_cycle():
    """Stuart-Landau cycle coupled to 8 stable linear modes (rotated by a random
    orthogonal S, so the transfer matrices are full).  Multipliers: 1,
    exp(-2 lam T) and exp(lambda_k T) (1e-30 .. 0.37).  For a linear mode,
    Gauss collocation on N intervals gives exactly R_m(h T lambda_k)^N (Pade),
    which isolates the eigenvalue algorithm's accuracy."""
    T = 2 * np.pi / W
    rng = np.random.default_rng(0)
    S, _ = np.linalg.qr(rng.normal(size=(NZ, NZ)))
    A = S @ np.diag(RATES_T / T) @ S.T
    sch, N = col.Scheme(4), 40
    o = col.orbit_from_function(
        lambda t: np.concatenate([np.sqrt(LAM) * np.stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)], 1),
                                  np.zeros((len(t), NZ))], 1), T * 1.01, LAM, sch, col.uniform_mesh(N))
    res = correct(stiff_field, jnp.asarray(A), o, col.natural_constraint(o, LAM))
    assert res.converged
    G = np.asarray(col.transfer_matrices(stiff_field, jnp.asarray(A), res.x, sch))
    out = floquet.multipliers_periodic(G)
    mu = np.sort(out.multipliers.real)[::-1]
    discrete = np.sort(np.concatenate([[1.0, np.exp(-2 * LAM * T)], _pade(RATES_T / N, 4) ** N]))[::-1]
    exact = np.sort(np.concatenate([[1.0, np.exp(-2 * LAM * T)], np.exp(RATES_T)]))[::-1]
    rel_discrete = np.abs(mu / discrete - 1)
    rel_exact = np.abs(mu / exact - 1)
    print("stable: rel. err vs discrete", rel_discrete, "vs exp", rel_exact)
    assert np.max(np.abs(out.multipliers.imag)) < 1e-12 * 0 + 1e-14
    assert np.max(rel_discrete[1:]) < 1e-8
    assert np.max(rel_exact) < 1e-3                     # discretisation error only
    assert floquet.trivial_error(out.multipliers) < 1e-12
    plain = np.sort(floquet.multipliers_product(G).real)[::-1]
    rel_plain = np.abs(plain / discrete - 1)
    print("plain: rel. err", rel_plain)
    assert rel_plain[-1] > 1.0                          # plain product: 1e-30 multiplier is round-off
