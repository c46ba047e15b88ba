"""Signal analyses on signals whose answer is known (no GFB model involved)."""

import math

import numpy as np
import pytest

from gfbjax.analyses.signals import (
    classify_poincare,
    lyapunov_rosenstein,
    poincare_section,
    runup_stft,
    spectrum,
    steady_state,
    subsynchronous,
)


def logistic(r, n=400, x0=0.2, burn=1000):
    x = x0
    for _ in range(burn):
        x = r * x * (1 - x)
    out = np.empty(n)
    for i in range(n):
        x = r * x * (1 - x)
        out[i] = x
    return out


def henon(n=500, a=1.4, b=0.3, burn=1000):
    x, y = 0.1, 0.1
    pts = []
    for i in range(burn + n):
        x, y = 1 - a * x * x + y, b * x
        if i >= burn:
            pts.append((x, y))
    return np.asarray(pts)


@pytest.mark.parametrize("r, k", [(3.2, 2), (3.5, 4)])
def test_logistic_period_k(r, k):
    c = classify_poincare(logistic(r))
    assert c.kind == f"period-{k}" and c.period == k and c.n_clusters == k


def test_logistic_r4_chaotic():
    c = classify_poincare(logistic(4.0))
    assert c.kind == "chaotic"
    assert c.lyapunov == pytest.approx(math.log(2), abs=0.25)


def test_henon_chaotic():
    c = classify_poincare(henon())
    assert c.kind == "chaotic"
    assert 0.2 < c.lyapunov < 0.7  # literature value 0.42


def test_two_frequency_signal_quasi_periodic():
    # x(t) = cos(t) + 0.4 cos(sqrt(2) t) + 0.1 cos(2 t): forcing period 2 pi, the second frequency incommensurate
    spr = 32
    t = np.arange(300 * spr + 1) * 2 * math.pi / spr
    x = np.cos(t) + 0.4 * np.cos(math.sqrt(2) * t) + 0.1 * np.cos(2 * t)
    v = -np.sin(t) - 0.4 * math.sqrt(2) * np.sin(math.sqrt(2) * t) - 0.2 * np.sin(2 * t)
    P = poincare_section(np.stack([x, v], 1), spr)
    c = classify_poincare(P)
    assert c.kind == "quasi-periodic", c.message
    assert abs(c.lyapunov) < 0.05


def _duffing_poincare(gamma, n=260, keep=120):
    import diffrax as dfx
    import jax.numpy as jnp

    delta, omega = 0.3, 1.2
    T = 2 * math.pi / omega

    def f(t, y, a):
        return jnp.array([y[1], -delta * y[1] + y[0] - y[0] ** 3 + a * jnp.cos(omega * t)])

    sol = dfx.diffeqsolve(dfx.ODETerm(f), dfx.Tsit5(), 0.0, n * T, 0.01, jnp.array([1.0, 0.0]), args=gamma,
                          saveat=dfx.SaveAt(ts=jnp.arange(n + 1) * T),
                          stepsize_controller=dfx.PIDController(rtol=1e-10, atol=1e-12), max_steps=10**6)
    return np.asarray(sol.ys)[-keep:]


@pytest.mark.parametrize("gamma, kind", [(0.20, "period-1"), (0.28, "period-2"), (0.50, "chaotic")])
def test_forced_duffing(gamma, kind):
    """Double-well Duffing x'' + 0.3 x' - x + x^3 = gamma cos(1.2 t) from (1, 0): Jordan & Smith (2007), ch. 13."""
    c = classify_poincare(_duffing_poincare(gamma))
    assert c.kind == kind, c.message


def test_fft_pure_1x():
    speed, spr, revs = 0.37, 32, 40
    dt = 2 * math.pi / speed / spr
    t = np.arange(revs * spr) * dt
    x = 0.3 * np.cos(speed * t + 0.4) + 0.05
    s = spectrum(x, dt, speed)
    order, amp = s.peak()
    assert order == pytest.approx(1.0, abs=1e-12)
    assert amp == pytest.approx(0.3, rel=1e-9)
    o2, a2 = s.peak(0.05, 0.9)
    assert a2 < 1e-10


def test_fft_half_order():
    speed, spr, revs = 1.0, 16, 64
    dt = 2 * math.pi / speed / spr
    t = np.arange(revs * spr) * dt
    s = spectrum(np.cos(speed * t) + 0.2 * np.sin(0.5 * speed * t), dt, speed)
    assert s.peak(0.1, 0.9) == pytest.approx((0.5, 0.2), rel=1e-9)


def test_stft_runup_subsynchronous_onset():
    # chirp from speed 0.2 to 1.0: a 1X component and, from speed 0.6 on, a fixed-frequency whirl at omega = 0.25
    w0, w1, T = 0.2, 1.0, 3000.0
    a = (w1 - w0) / T
    dt = 2 * math.pi / (w1 * 32)
    t = np.arange(0, T, dt)
    speed = w0 + a * t
    phase = w0 * t + 0.5 * a * t * t
    x = 0.1 * np.cos(phase) + np.where(speed > 0.6, 0.05, 0.0) * np.cos(0.25 * t)
    sg = runup_stft(t, x, speed, segment_revs=12)
    assert np.all(np.diff(sg.speed) > 0)
    k = np.argmin(np.abs(sg.speed - 0.4))
    assert sg.order[np.argmax(sg.order_amplitude[k])] == pytest.approx(1.0, abs=0.1)  # bin: 0.2 orders at 0.4
    ranges = subsynchronous(sg)
    assert len(ranges) == 1
    r = ranges[0]
    assert r.speed_start == pytest.approx(0.6, abs=0.06) and r.speed_end > 0.9
    assert r.omega == pytest.approx(0.25, abs=0.02)


def test_steady_state_of_decaying_oscillation():
    spr = 32
    t = np.arange(200 * spr) * 2 * math.pi / spr
    x = np.cos(t) + np.exp(-0.05 * t) * np.cos(0.3 * t)
    st = steady_state(x, spr, window=10, tol=1e-3)
    assert st.steady and 10 <= st.start_rev <= 60
    assert not steady_state(x[: 30 * spr], spr, window=10, tol=1e-3).steady


def test_lyapunov_of_rotation_is_zero():
    n = np.arange(400)
    th = 2 * math.pi * (math.sqrt(5) - 1) / 2 * n
    assert abs(lyapunov_rosenstein(np.stack([np.cos(th), np.sin(th)], 1))) < 0.02
