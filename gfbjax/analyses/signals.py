"""Signal analyses of transient responses (paper Sect. 3.2, panels b-c of Figs. 7-11): steady-state detection,
Poincare sections, FFT in multiples of the running speed, STFT of a run-up against speed, and the classification of
a steady response as period-1, period-k, quasi-periodic or chaotic from its Poincare points.

Plain numpy on sampled signals; nothing here knows about bearings.  Frequencies are *orders* (multiples of the
running frequency ``Omega / 2 pi``) or dimensionless angular frequencies ``omega`` [rad per tau] (``1X`` is
``omega = Omega``).

Classification (:func:`classify_poincare`), thresholds documented there:

1. **period-k**: the smallest ``k <= max_period`` with ``max_i |P_{i+k} - P_i| <= period_tol * scale`` (the
   Poincare series repeats itself after k revolutions; ``scale`` is the size of the response);
2. otherwise **chaotic** when the largest Lyapunov exponent of the Poincare series (Rosenstein et al. 1993:
   mean log divergence of nearest neighbours, slope over the first ``fit_steps`` iterations) exceeds
   ``lyap_threshold`` per revolution, else **quasi-periodic** (points on a closed invariant curve: neighbours stay
   neighbours, exponent ~ 0);
3. **undetermined** with too few points (< ``min_points``).

Known answers used by the tests: logistic map (r = 3.2 period 2, r = 3.5 period 4, r = 4 chaotic with exponent
ln 2), Henon map (chaotic, exponent 0.42), a two-frequency signal with incommensurate frequencies (quasi-periodic),
the forced double-well Duffing oscillator ``x'' + 0.3 x' - x + x^3 = gamma cos(1.2 t)`` (period 1 at gamma = 0.20,
period 2 at 0.28, period 4 at 0.29, period 5 at 0.37, chaotic at 0.50; Jordan & Smith, *Nonlinear Ordinary
Differential Equations*, 4th ed., OUP 2007, ch. 13, and the figures of Wikipedia's "Duffing equation").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

__all__ = [
    "poincare_section",
    "SteadyState",
    "steady_state",
    "Spectrum",
    "spectrum",
    "Spectrogram",
    "runup_stft",
    "SubsyncRange",
    "subsynchronous",
    "Classification",
    "classify_poincare",
    "classify_response",
    "lyapunov_rosenstein",
    "orbit",
    "delay_embed",
]


# -- Poincare section and steady state ---------------------------------------------------------------------------


def poincare_section(x: np.ndarray, samples_per_rev: int, offset: int = 0, last: int | None = None) -> np.ndarray:
    """Once-per-revolution samples ``x[offset::samples_per_rev]`` of a constant-speed signal sampled
    ``samples_per_rev`` times per revolution (``offset = 0``: unbalance phase 0).  ``last`` keeps the last
    ``last`` revolutions (the paper plots the last 100 of 500)."""
    x = np.asarray(x)
    pts = x[offset::samples_per_rev]
    return pts if last is None else pts[-last:]


@dataclass
class SteadyState:
    """Result of :func:`steady_state`.

    Attributes:
        steady: the last ``window`` revolutions are steady (their envelope matches the previous window's).
        start_rev: first revolution from which every window's envelope stays within tolerance of the last one
            (None when not steady).
        drift: relative change of the envelope between the last two windows.
    """

    steady: bool
    start_rev: int | None
    drift: float


def steady_state(x: np.ndarray, samples_per_rev: int, window: int = 10, tol: float = 2e-3) -> SteadyState:
    """Detect the steady state of a constant-speed response ``x`` (shape (M,) or (M, d)).

    The envelope of each block of ``window`` revolutions is its per-coordinate (min, max, mean).  The response is
    steady when the envelope of the last block differs from the one before by at most ``tol`` times the response
    size (the peak-to-peak over the last block, at least 1e-12); ``start_rev`` is the first block boundary after
    which every block agrees with the last block to that tolerance.  Periodic responses settle to round-off; for
    quasi-periodic or chaotic ones use a longer ``window`` (and a looser ``tol``) so that a block covers the
    envelope.
    """
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    n = window * samples_per_rev
    nblk = x.shape[0] // n
    if nblk < 2:
        return SteadyState(False, None, math.inf)
    start = x.shape[0] - nblk * n
    blocks = x[start:].reshape(nblk, n, -1)
    env = np.concatenate([blocks.min(1), blocks.max(1), blocks.mean(1)], axis=1)
    scale = max(float(np.ptp(blocks[-1], axis=0).max()), float(np.abs(blocks[-1]).max()) * 1e-6, 1e-12)
    dev = np.abs(env - env[-1]).max(axis=1) / scale
    drift = float(dev[-2])
    if drift > tol:
        return SteadyState(False, None, drift)
    bad = np.where(dev > tol)[0]
    first = 0 if bad.size == 0 else int(bad[-1]) + 1
    return SteadyState(True, (start // samples_per_rev) + first * window, drift)


def orbit(x: np.ndarray, y: np.ndarray, samples_per_rev: int, revolutions: int | None = None
          ) -> tuple[np.ndarray, np.ndarray]:
    """The last ``revolutions`` revolutions of the orbit (x, y) (all of it when None)."""
    if revolutions is None:
        return np.asarray(x), np.asarray(y)
    n = revolutions * samples_per_rev + 1
    return np.asarray(x)[-n:], np.asarray(y)[-n:]


# -- spectra --------------------------------------------------------------------------------------------------------


@dataclass
class Spectrum:
    """Single-sided amplitude spectrum.  ``order``: frequency over the running frequency; ``omega``: angular
    frequency [rad per tau]; ``amplitude``: amplitude of each harmonic component (a pure ``A cos`` at a bin gives
    ``A``), in the signal's units."""

    order: np.ndarray
    omega: np.ndarray
    amplitude: np.ndarray

    def peak(self, lo: float = 0.0, hi: float = math.inf) -> tuple[float, float]:
        """(order, amplitude) of the largest component with ``lo <= order <= hi``."""
        m = (self.order >= lo) & (self.order <= hi)
        if not m.any():
            return math.nan, 0.0
        i = np.flatnonzero(m)[np.argmax(self.amplitude[m])]
        return float(self.order[i]), float(self.amplitude[i])


def _window(name: str, n: int) -> np.ndarray:
    if name == "hann":
        return np.hanning(n + 1)[:-1] if n > 1 else np.ones(n)  # periodic Hann
    if name in ("rect", "boxcar", "none"):
        return np.ones(n)
    raise ValueError(f"window = {name!r} is not one of 'hann', 'rect'")


def spectrum(x: np.ndarray, dtau: float, speed: float, window: str = "hann", detrend: bool = True) -> Spectrum:
    """Amplitude spectrum of a constant-speed response ``x`` sampled every ``dtau``, frequencies in multiples of
    the running speed ``speed`` (Omega_bar).  Use an integer number of revolutions for exact 1X bins (e.g.
    ``TransientResult.window(revs)``).  The mean is removed (``detrend``); the window's coherent gain is
    corrected so that a component at a bin shows its true amplitude."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 4:
        raise ValueError("spectrum needs a 1-D signal of at least 4 samples")
    if detrend:
        x = x - x.mean()
    w = _window(window, x.size)
    X = np.fft.rfft(x * w)
    amp = np.abs(X) * 2.0 / w.sum()
    amp[0] /= 2.0
    if x.size % 2 == 0:
        amp[-1] /= 2.0
    f = np.fft.rfftfreq(x.size, d=dtau)  # cycles per tau
    om = 2 * math.pi * f
    return Spectrum(order=om / speed, omega=om, amplitude=amp)


@dataclass
class Spectrogram:
    """Short-time Fourier transform of a run-up.

    Attributes:
        tau: centre time of each segment, (S,).
        speed: mean running speed Omega_bar of each segment, (S,).
        omega: angular frequencies [rad per tau] of the raw transform, (F,).
        amplitude: amplitude at (segment, omega), (S, F).
        order: common order grid (multiples of each segment's running speed), (O,).
        order_amplitude: amplitude interpolated to (segment, order), (S, O).
        segment_revs: revolutions covered by one segment at each segment's speed, (S,).
    """

    tau: np.ndarray
    speed: np.ndarray
    omega: np.ndarray
    amplitude: np.ndarray
    order: np.ndarray
    order_amplitude: np.ndarray
    segment_revs: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)


def runup_stft(tau: np.ndarray, x: np.ndarray, speed: np.ndarray, *, segment: float | None = None,
               segment_revs: float = 12.0, overlap: float = 0.75, max_order: float = 3.0, n_orders: int = 601,
               window: str = "hann") -> Spectrogram:
    """STFT of a run-up (or coast-down) response sampled uniformly in tau, as a spectrogram against speed.
    Each segment is linearly detrended and Hann-windowed.

    Args:
        tau, x, speed: sample times, signal and running speed at each sample (uniform tau spacing).
        segment: segment length in tau; default ``segment_revs`` revolutions at the highest speed of the run.
        overlap: fraction of overlap of consecutive segments, in [0, 0.95].
        max_order, n_orders: the common order grid ``[0, max_order]`` onto which each segment's spectrum is
            interpolated (each with its own mean speed), for plots in multiples of the running frequency.
        window: ``"hann"`` or ``"rect"``.
    """
    tau = np.asarray(tau, float)
    x = np.asarray(x, float)
    speed = np.asarray(speed, float)
    if tau.size < 16:
        raise ValueError("runup_stft needs at least 16 samples")
    if not 0.0 <= overlap <= 0.95:
        raise ValueError(f"overlap = {overlap!r} is outside the allowed range [0, 0.95]")
    dtau = float(np.median(np.diff(tau)))
    if segment is None:
        segment = segment_revs * 2 * math.pi / float(np.max(np.abs(speed)))
    nper = int(min(max(16, tau.size // 4), max(16, round(segment / dtau))))  # at least ~4-7 segments
    hop = max(1, int(round(nper * (1.0 - overlap))))
    starts = np.arange(0, tau.size - nper + 1, hop)
    w = _window(window, nper)
    omega = 2 * math.pi * np.fft.rfftfreq(nper, d=dtau)
    amps, tc, sc = [], [], []
    for s0 in starts:
        seg = x[s0:s0 + nper]
        tt = np.arange(nper)
        seg = seg - np.polyval(np.polyfit(tt, seg, 1), tt)  # linear detrend: the equilibrium drifts with speed
        X = np.fft.rfft(seg * w)
        a = np.abs(X) * 2.0 / w.sum()
        amps.append(a)
        tc.append(tau[s0:s0 + nper].mean())
        sc.append(speed[s0:s0 + nper].mean())
    amp = np.asarray(amps)
    sc = np.asarray(sc)
    orders = np.linspace(0.0, max_order, n_orders)
    oamp = np.stack([np.interp(orders * abs(s), omega, a, right=0.0) for s, a in zip(sc, amp)])
    return Spectrogram(tau=np.asarray(tc), speed=sc, omega=omega, amplitude=amp, order=orders,
                       order_amplitude=oamp, segment_revs=np.abs(sc) * nper * dtau / (2 * math.pi),
                       meta={"segment_tau": nper * dtau, "samples_per_segment": nper, "hop": hop,
                             "window": window, "overlap": overlap})


@dataclass
class SubsyncRange:
    """A speed range with a sub-synchronous component (from :func:`subsynchronous`).

    Attributes: ``speed_start``, ``speed_end`` (Omega_bar of the first and last segment); ``order`` and ``omega``
    (order and angular frequency [rad/tau] of the strongest sub-synchronous peak in the range); ``rel_amplitude``
    (its amplitude over the 1X amplitude of its segment); ``amplitude`` (absolute)."""

    speed_start: float
    speed_end: float
    order: float
    omega: float
    amplitude: float
    rel_amplitude: float


def subsynchronous(sg: Spectrogram, *, band: tuple[float, float] = (0.1, 0.9), rel: float = 0.1,
                   floor: float = 1e-3, min_segments: int = 2) -> list[SubsyncRange]:
    """Speed ranges where the STFT shows a sub-synchronous component.

    A segment has one when the largest amplitude at orders in ``band`` (excluding the main lobe of the 1X line:
    within two frequency bins of 1X, at each segment's speed, and the lowest two bins) is a local maximum that exceeds both ``rel`` times the segment's 1X amplitude and the absolute
    ``floor`` (units of the signal, e.g. 1e-3 c).  Consecutive segments with one form a range; ranges shorter than
    ``min_segments`` segments are dropped (isolated spikes).
    """
    lo, hi = band
    o = sg.order
    m = (o >= lo) & (o <= hi)
    hits = []
    dw = 2 * math.pi / sg.meta["segment_tau"] if sg.meta.get("segment_tau") else 0.0
    for k in range(sg.order_amplitude.shape[0]):
        a = sg.order_amplitude[k]
        a1 = float(np.interp(1.0, o, a))
        om_k = o * abs(sg.speed[k])
        mk = m & (np.abs(om_k - abs(sg.speed[k])) > 2.0 * dw) & (om_k > 2.0 * dw)  # off the 1X and DC lobes
        if not mk.any():
            hits.append(None)
            continue
        idx = np.flatnonzero(mk)
        j = idx[np.argmax(a[idx])]
        is_peak = 0 < j < o.size - 1 and a[j] >= a[j - 1] and a[j] >= a[j + 1]
        if is_peak and a[j] > rel * max(a1, 1e-300) and a[j] > floor:
            hits.append((float(o[j]), float(a[j]), float(a[j] / max(a1, 1e-300))))
        else:
            hits.append(None)
    out: list[SubsyncRange] = []
    k = 0
    while k < len(hits):
        if hits[k] is None:
            k += 1
            continue
        k0 = k
        while k < len(hits) and hits[k] is not None:
            k += 1
        if k - k0 >= min_segments:
            seg = hits[k0:k]
            best = max(range(len(seg)), key=lambda i: seg[i][1])
            order, amp, r = seg[best]
            sp = sg.speed[k0 + best]
            out.append(SubsyncRange(float(sg.speed[k0]), float(sg.speed[k - 1]), order, order * abs(sp), amp, r))
    return out


# -- classification --------------------------------------------------------------------------------------------------


@dataclass
class Classification:
    """Result of :func:`classify_poincare`.

    Attributes:
        kind: ``"period-1"``, ``"period-k"`` (k = ``period``), ``"quasi-periodic"``, ``"chaotic"`` or
            ``"undetermined"``.
        period: k for periodic responses, else None.
        period_errors: ``max_i |P_{i+k} - P_i| / scale`` for k = 1..max_period.
        lyapunov: largest Lyapunov exponent estimate per revolution (None for periodic responses).
        n_points: Poincare points used.
        n_clusters: distinct points at the tolerance ``period_tol * scale`` (a check of k for periodic responses).
        message: one sentence.
    """

    kind: str
    period: int | None
    period_errors: np.ndarray
    lyapunov: float | None
    n_points: int
    n_clusters: int
    message: str

    @property
    def periodic(self) -> bool:
        return self.period is not None


def delay_embed(x: np.ndarray, dim: int = 2, lag: int = 1) -> np.ndarray:
    """Delay vectors ``(x_i, x_{i+lag}, ..., x_{i+(dim-1) lag})`` of a scalar series, shape (K - (dim-1) lag, dim)."""
    x = np.asarray(x, float).ravel()
    n = x.size - (dim - 1) * lag
    if n <= 0:
        raise ValueError("series too short for this embedding")
    return np.stack([x[i * lag: i * lag + n] for i in range(dim)], axis=1)


def lyapunov_rosenstein(points: np.ndarray, fit_steps: int = 5, min_separation: int = 1) -> float:
    """Largest Lyapunov exponent per iteration of a map from its orbit ``points`` (K, d), after Rosenstein,
    Collins & De Luca, Physica D 65 (1993) 117: each point's nearest neighbour (at least ``min_separation``
    iterations apart) is followed for ``fit_steps`` iterations; the exponent is the least-squares slope of the
    mean log distance against the iteration.  Coordinates are scaled to unit range first."""
    P = np.asarray(points, float)
    if P.ndim == 1:
        P = P[:, None]
    rng = np.ptp(P, axis=0)
    P = P / np.where(rng > 0, rng, 1.0)
    K = P.shape[0]
    J = int(fit_steps)
    n = K - J
    if n < 5:
        return math.nan
    D = np.sqrt(((P[:n, None, :] - P[None, :n, :]) ** 2).sum(-1))
    idx = np.arange(n)
    D[np.abs(idx[:, None] - idx[None, :]) < max(1, min_separation)] = np.inf
    nn = np.argmin(D, axis=1)
    d0 = D[idx, nn]
    ok = np.isfinite(d0) & (d0 > 0)
    i, j = idx[ok], nn[ok]
    if i.size < 3:
        return math.nan
    L = []
    for s in range(J + 1):
        d = np.sqrt(((P[i + s] - P[j + s]) ** 2).sum(-1))
        L.append(np.mean(np.log(np.maximum(d, 1e-300))))
    s = np.arange(J + 1)
    return float(np.polyfit(s, np.asarray(L), 1)[0])


def _clusters(P: np.ndarray, tol: float) -> int:
    reps: list[np.ndarray] = []
    for p in P:
        if not any(np.max(np.abs(p - r)) <= tol for r in reps):
            reps.append(p)
            if len(reps) > 64:
                break
    return len(reps)


def classify_poincare(points: np.ndarray, *, scale: float | None = None, period_tol: float = 1e-3,
                      max_period: int = 16, lyap_threshold: float = 0.05, fit_steps: int = 5,
                      min_points: int = 20) -> Classification:
    """Classify a steady response from its Poincare points (K, d) (a scalar series: (K,)).

    Thresholds (see the module docstring):

    * period-k: the smallest ``k <= max_period`` with ``max_i |P_{i+k} - P_i|_inf <= period_tol * scale``
      (needs at least ``2 k`` points); ``scale`` defaults to the largest of the points' peak-to-peak and
      magnitude, pass the orbit size (peak-to-peak of the time signal) for rotor responses.  1e-3 is well above
      integration noise at rtol 1e-6 and well below the spread of any bifurcated response;
    * chaotic vs quasi-periodic: the largest Lyapunov exponent per iteration
      (:func:`lyapunov_rosenstein`; 1-D series are delay-embedded in 2-D first) above ``lyap_threshold``
      (0.05: a quasi-periodic rotation gives |exponent| < 0.02 with a few hundred points; the logistic map at
      r = 4 gives ln 2, Henon 0.42).  Weak chaos (exponent < 0.05 per revolution) is reported as quasi-periodic.
    """
    P = np.asarray(points, float)
    if P.ndim == 1:
        P = P[:, None]
    K = P.shape[0]
    if scale is None:
        scale = max(float(np.ptp(P, axis=0).max()), float(np.abs(P).max()), 1e-12)
    errs = []
    for k in range(1, max_period + 1):
        if K - k < max(k, 2):
            break
        errs.append(float(np.abs(P[k:] - P[:-k]).max() / scale))
    errs_a = np.asarray(errs)
    ncl = _clusters(P, period_tol * scale)
    if K < min_points:
        return Classification("undetermined", None, errs_a, None, K, ncl,
                              f"only {K} Poincare points (need {min_points})")
    for k, e in enumerate(errs, start=1):
        if e <= period_tol:
            kind = "period-1" if k == 1 else f"period-{k}"
            return Classification(kind, k, errs_a, None, K, ncl,
                                  f"{kind}: the Poincare series repeats after {k} revolution(s) to {e:.1e} of the "
                                  f"response size; {ncl} distinct point(s)")
    Z = delay_embed(P[:, 0], 2) if P.shape[1] == 1 else P
    lam = lyapunov_rosenstein(Z, fit_steps=fit_steps)
    if not math.isfinite(lam):
        return Classification("undetermined", None, errs_a, lam, K, ncl, "Lyapunov estimate failed")
    if lam > lyap_threshold:
        return Classification("chaotic", None, errs_a, lam, K, ncl,
                              f"chaotic: not periodic up to {len(errs)} revolutions, largest Lyapunov exponent "
                              f"{lam:.3f} per revolution > {lyap_threshold:g}")
    return Classification("quasi-periodic", None, errs_a, lam, K, ncl,
                          f"quasi-periodic: not periodic up to {len(errs)} revolutions, neighbours do not diverge "
                          f"(exponent {lam:.3f} per revolution <= {lyap_threshold:g})")


def classify_response(result: Any, last: int = 100, coords: Sequence[int] = (0, 1, 4, 5), **kwargs: Any
                      ) -> Classification:
    """Classify the last ``last`` revolutions of a constant-speed :class:`gfbjax.analyses.transient.TransientResult` from
    its Poincare points in the rotor coordinates ``coords`` (default journal position and velocity; the rigid
    rotor's velocities are columns 2, 3).  ``scale`` is the peak-to-peak of the journal orbit over those
    revolutions (the paper: the last 100 of 500)."""
    P = result.poincare(last=last)
    cols = [c for c in coords if c < P.shape[1]]
    if result.rotor_kind == "rigid":
        cols = [c for c in (0, 1, 2, 3) if c < P.shape[1]]
    sl = result.window(last)
    seg = result.rotor[sl][:, cols]
    size = np.ptp(seg, axis=0)  # orbit size per coordinate over the same revolutions
    size = np.where(size > 1e-12, size, 1.0)
    return classify_poincare(P[:, cols] / size, scale=1.0, **kwargs)
