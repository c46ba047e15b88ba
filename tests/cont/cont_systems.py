"""Small test systems with analytically known behaviour (shared by the tests)."""
import jax.numpy as jnp
import numpy as np


def stuart_landau(x, lam, w):
    """Supercritical Hopf normal form: cycle radius sqrt(lam), period 2 pi / w,
    multipliers {1, exp(-2 lam T)}."""
    r2 = x[0] ** 2 + x[1] ** 2
    return jnp.array([lam * x[0] - w * x[1] - x[0] * r2, w * x[0] + lam * x[1] - x[1] * r2])


def stuart_landau_sub(x, lam, w):
    """Subcritical variant r' = r (lam + r^2 - r^4): cycles at lam = r^4 - r^2,
    emanating to lam < 0 at the Hopf point, fold of cycles at r^2 = 1/2, lam = -1/4."""
    r2 = x[0] ** 2 + x[1] ** 2
    g = lam + r2 - r2 ** 2
    return jnp.array([g * x[0] - w * x[1], w * x[0] + g * x[1]])


def van_der_pol(x, lam, mu):
    """x'' - mu (1 - x^2) x' + x = 0 (lam unused)."""
    return jnp.array([x[1], mu * (1.0 - x[0] ** 2) * x[1] - x[0]])


def forced_duffing(z, gamma, p):
    """Forced double-well Duffing x'' + d x' - x + x^3 = gamma cos(w t), written
    autonomously with the oscillator u' = u + w s - u(u^2+s^2),
    s' = -w u + s - s(u^2+s^2) whose attracting cycle is (cos wt, -sin wt)."""
    d, w = p[0], p[1]
    x, v, u, s = z[0], z[1], z[2], z[3]
    r2 = u * u + s * s
    return jnp.array([v, -d * v + x - x ** 3 + gamma * u, u + w * s - u * r2, -w * u + s - s * r2])


def fold_1d(x, lam, args):
    """x' = lam - x^2: fold of equilibria at lam = 0, x = 0."""
    return jnp.array([lam - x[0] ** 2])


def torus_field(x, lam, p):
    """Stuart-Landau cycle (x0, x1) times a linear oscillator (x2, x3) with
    growth rate lam - 1/2 and frequency nu.  Non-trivial multipliers:
    exp(-2 lam T) and exp((lam - 1/2 +- i nu) T), T = 2 pi / w; the complex pair
    crosses the unit circle at lam = 1/2 with angle nu T (mod 2 pi):
    a Neimark-Sacker (torus) bifurcation with known parameter and angle."""
    w, nu = p[0], p[1]
    r2 = x[0] ** 2 + x[1] ** 2
    a = lam - 0.5
    return jnp.array([lam * x[0] - w * x[1] - x[0] * r2, w * x[0] + lam * x[1] - x[1] * r2,
                      a * x[2] - nu * x[3], nu * x[2] + a * x[3]])


def mathieu_duffing(z, a, p):
    """Mathieu-Duffing x'' + (a - 2 q cos 2t) x + beta x^3 = 0, written autonomously with the oscillator
    u' = u + 2 s - u(u^2+s^2), s' = -2 u + s - s(u^2+s^2), attracting cycle (cos 2t, -sin 2t) of period pi.
    x = 0 is a cycle for every a; its stability is Mathieu's: multipliers -1 on the characteristic curves
    a = a_1(q), b_1(q) (period-2 pi Mathieu functions ce_1, se_1)."""
    q, beta = p[0], p[1]
    x, v, u, s = z[0], z[1], z[2], z[3]
    r2 = u * u + s * s
    return jnp.array([v, -(a - 2.0 * q * u) * x - beta * x ** 3, u + 2.0 * s - u * r2, -2.0 * u + s - s * r2])


def correct(f, args, orbit, con=None, *, max_iter=12, tol=1e-10):
    """One dense cycle correction through the public API (the NewtonSolution; ``x`` is the orbit)."""
    from gfbjax.cont import CycleProblem, CycleSettings, DenseCondensation, correct_cycle
    settings = CycleSettings(m=int(orbit.xi.shape[1]) + 1, newton_tol=tol, newton_step_tol=tol,
                             newton_max_iter=max_iter, fast_iter=min(3, max_iter), linear_solver=DenseCondensation())
    sol, _ = correct_cycle(CycleProblem(f, orbit.n, args), orbit, con, settings=settings)
    return sol
