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


def half_turn_field(x, lam, p):
    """A stable unit-circle oscillator (u, v) with frequency w, driving a linear planar system z that turns by
    half a revolution per period, in 4 states.  p = (w, gamma0, dgamma, delta, mu0, dmu): gamma = gamma0 + lam
    dgamma, mu = mu0 + lam dmu.

        u' = u - w v - u (u^2 + v^2),   v' = w u + v - v (u^2 + v^2)
        z' = [ (w/2) J + gamma I + delta J + mu S(u, v) ] z,   S = [[u, v], [v, -u]],  J = [[0, -1], [1, 0]]

    On the cycle (u, v) = (cos wt, sin wt), z = 0, T = 2 pi / w.  In the frame turning at half the oscillator's
    speed the z-system is constant, D = gamma I + delta J + mu diag(1, -1), so the Floquet multipliers are, in
    closed form, 1 (trivial), exp(-2T) and -exp((gamma +- sqrt(mu^2 - delta^2)) T): two negative reals for
    mu > delta, a complex pair of modulus exp(gamma T) and angle pi - sqrt(delta^2 - mu^2) T for mu < delta.

    An optional seventh parameter c adds c u I to the z-system: it commutes with the rest and integrates to zero
    over a period, so the multipliers keep their closed form, but a coarse collocation mesh no longer reproduces
    them exactly (a known discretisation error in the location of the PD and NS)."""
    w, g0, dg, d, m0, dm = p[0], p[1], p[2], p[3], p[4], p[5]
    u, v, z1, z2 = x[0], x[1], x[2], x[3]
    g = g0 + lam * dg + (p[6] * u if p.shape[0] > 6 else 0.0)
    m = m0 + lam * dm
    r2 = u * u + v * v
    rot = 0.5 * w + d
    dz1 = (g + m * u) * z1 + (m * v - rot) * z2
    dz2 = (m * v + rot) * z1 + (g - m * u) * z2
    return jnp.stack([u - w * v - u * r2, w * u + v - v * r2, dz1, dz2])


def half_turn_multipliers(p, lam):
    """The closed-form non-trivial multipliers of ``half_turn_field`` at lam (see there), T = 2 pi / w."""
    w, g0, dg, d, m0, dm = (float(v) for v in p[:6])
    T = 2 * np.pi / w
    g, m = g0 + lam * dg, m0 + lam * dm
    s = np.sqrt(complex(m * m - d * d))
    return np.array([np.exp(-2 * T), -np.exp((g + s) * T), -np.exp((g - s) * T)])


def two_hopf_pairs(x, lam, args):
    """Two independent Hopf normal forms in 4 states: eigenvalues (lam - 1) +- 1.0 i and (lam - 2) +- 1.7 i at
    x = 0, so Hopf points at lam = 1 (omega 1.0) and lam = 2 (omega 1.7)."""
    def hopf(a, b, s, w):
        r2 = a * a + b * b
        return s * a - w * b - a * r2, w * a + s * b - b * r2
    d1, d2 = hopf(x[0], x[1], lam - 1.0, 1.0)
    d3, d4 = hopf(x[2], x[3], lam - 2.0, 1.7)
    return jnp.stack([d1, d2, d3, d4])


def saddle_family(x, lam, args):
    """x' = lam x + y, y' = x + lam y, z' = -3 z: eigenvalues lam +- 1 and -3; at lam = 0 the real pair is +-1
    (neutral saddle: mu_1 + mu_2 = 2 lam = 0), and there is no Hopf point."""
    return jnp.stack([lam * x[0] + x[1], x[0] + lam * x[1], -3.0 * x[2]])


def ring(x, lam, p):
    """A ring of k diffusively coupled Hopf oscillators (n = 2k, p = (w, d)): the synchronous cycle of radius
    sqrt(lam), period 2 pi / w, with multipliers exp(-(2 lam + dq) T) and exp(-dq T), dq = 4 d sin^2(pi q / k)."""
    w, d = p[0], p[1]
    a, b = x[0::2], x[1::2]
    r2 = a * a + b * b
    lap = lambda u: jnp.roll(u, 1) - 2 * u + jnp.roll(u, -1)  # noqa: E731
    da = lam * a - w * b - a * r2 + d * lap(a)
    db = w * a + lam * b - b * r2 + d * lap(b)
    return jnp.stack([da, db], axis=1).ravel()


def ring_pattern(k):
    """The Jacobian pattern of :func:`ring` with k oscillators (nearest neighbours on the ring)."""
    n = 2 * k
    P = np.zeros((n, n), bool)
    for i in range(k):
        for j in (i - 1, i, i + 1):
            jj = j % k
            P[2 * i:2 * i + 2, 2 * jj:2 * jj + 2] = True
    return P


def pd_family(x, lam, p):
    """A period doubling with its period-doubled family in closed form, in 4 states.  p = (w, mu, sat): the
    unit-circle oscillator (u, v) of ``half_turn_field`` (period T = 2 pi / w) drives z, which turns by half a
    revolution per period, with gain g = lam - mu - sat |z|^2:

        z' = [ (w/2) J + g I + mu S(u, v) ] z,   S = [[u, v], [v, -u]].

    In the frame turning at w/2 the z-system is z' = (g I + mu diag(1, -1)) z.  On z = 0 (period T) the non-trivial
    multipliers are exp(-2T) and -exp((lam - mu +- mu) T): a PD at lam = 0.  The doubled cycles (period 2T) are the
    frame's equilibria on its first axis, lam - sat |z|^2 = 0: |z| = sqrt(lam / sat), for lam > 0 when sat > 0
    (supercritical), lam < 0 when sat < 0; peak-to-peak of z1 or z2 over 2T: 2 |z|.  The cycle at z and at -z is
    one cycle shifted by T."""
    w, mu, sat = p[0], p[1], p[2]
    u, v, z1, z2 = x[0], x[1], x[2], x[3]
    r2 = u * u + v * v
    g = lam - mu - sat * (z1 * z1 + z2 * z2)
    rot = 0.5 * w
    dz1 = (g + mu * u) * z1 + (mu * v - rot) * z2
    dz2 = (mu * v + rot) * z1 + (g - mu * u) * z2
    return jnp.stack([u - w * v - u * r2, w * u + v - v * r2, dz1, dz2])
