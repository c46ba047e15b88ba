"""Figure functions of gfbjax.plot: drawing into given axes (``ax=``), overlaying several branches, the checks on
``ax`` and saving (``path=``).  Small hand-made results only; no solver runs."""

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from gfbjax.analyses.energy import CycleEnergy  # noqa: E402
from gfbjax.analyses.signals import Spectrogram  # noqa: E402
from gfbjax.analyses.static import StaticResult  # noqa: E402
from gfbjax.analyses.transient import TransientResult  # noqa: E402
from gfbjax.cont import Branch, Outcome, PointRecord, SpecialPoint  # noqa: E402
from gfbjax.design.schedule import Schedule  # noqa: E402
from gfbjax.plot import branch as pb, static as ps, transient as pt  # noqa: E402

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


# -- hand-made results -------------------------------------------------------------------------------------------


def cycles(shift: float = 0.0, ns_row: int = 4) -> Branch:
    """9 cycles, unstable from the NS point (row 4, located) on; a PD only bracketed (unlocated); row 2 flagged.
    ``ns_row``: where the NS point is drawn (8: at the right edge of the speed range)."""
    lams = np.linspace(0.30, 0.50, 9)
    pts = []
    for i, lam in enumerate(lams):
        r = 0.8 + 0.05 * i
        mu = np.array([1.0, r * np.exp(0.7j), r * np.exp(-0.7j), 0.1 + 0j])
        pts.append(PointRecord(lam=lam, period=2 * math.pi / lam, l2=0.5, xmax=np.array([0.2, -0.4]) + shift + 0.02 * i,
                               xmin=np.array([-0.2, -0.7]) + shift - 0.02 * i, multipliers=mu, stable=r < 1.0,
                               trivial_error=0.5 if i == 2 else 1e-4, newton_iterations=3, ds=0.02, tangent_lam=1.0))
    special = [SpecialPoint("NS", lam=float(lams[ns_row]), index=ns_row, spectrum=pts[ns_row].multipliers, located=True),
               SpecialPoint("PD", lam=0.47, index=8, spectrum=pts[8].multipliers, located=False)]
    return Branch.from_points("cycles", [0, 1], pts, special, [], Outcome.REACHED_END, m=3, accuracy_tol=0.1)


def equilibria(shift: float = 0.0) -> Branch:
    """7 equilibria, unstable past a located Hopf point (row 3); an unlocated fold."""
    lams = np.linspace(0.1, 0.4, 7)
    pts = []
    for i, lam in enumerate(lams):
        re = -0.3 + 0.1 * i
        ev = np.array([re + 1j, re - 1j, -2.0 + 0j])
        x = np.array([0.1 + shift + 0.01 * i, -0.6 + shift + 0.03 * i])
        pts.append(PointRecord(lam=lam, period=math.nan, l2=1.0, xmax=x, xmin=x, multipliers=ev, stable=re < 0,
                               trivial_error=math.nan, newton_iterations=2, ds=0.05, tangent_lam=1.0))
    special = [SpecialPoint("HOPF", lam=float(lams[3]), index=3, spectrum=pts[3].multipliers, located=True),
               SpecialPoint("FOLD", lam=0.38, index=6, spectrum=pts[6].multipliers, located=False)]
    return Branch.from_points("equilibria", [0, 1], pts, special, [], Outcome.REACHED_END)


def energy(b: Branch, scale: float = 1.0) -> CycleEnergy:
    lam = np.asarray(b.lam)
    W_cb = scale * (0.4 - lam)  # changes sign at 0.4
    return CycleEnergy(W_fu=scale * lam, W_B=scale * lam, W_cf=scale * 0.5 * lam, W_cb=W_cb)


def schedule() -> Schedule:
    s = Schedule("max_mu", "gradient")
    for i, w in enumerate([0.3, 0.32, 0.34]):
        mu = 0.9 + 0.06 * i
        s.omega.append(w)
        s.alpha_f.append(0.1 / (i + 1))
        s.eta.append(0.05 * (i + 1))
        s.W_cb.append(0.01 - 0.006 * i)
        s.max_mu.append(mu)
        s.stable.append(mu < 1.0)
        s.journal_max.append(np.array([0.45, -0.45]) + 0.01 * i)
        s.journal_min.append(np.array([0.4, -0.6]) - 0.01 * i)
        s.multipliers.append(np.array([1.0, mu * np.exp(0.9j), mu * np.exp(-0.9j), 0.2]))
    return s


def static_result(w: float, omega: float = 1.0, outcome: str = "converged") -> StaticResult:
    theta = np.linspace(math.pi / 2, math.pi / 2 + 2 * math.pi, 25)
    z = np.linspace(0.0, 0.5, 5)
    p = 1.0 + 0.3 * w * np.outer(np.maximum(-np.sin(theta), -0.2), np.sin(math.pi * z))
    ev = np.array([-0.01 + 0.4j, -0.01 - 0.4j, -0.5 + 2j, -0.5 - 2j, -30.0, -4000.0])
    y = -0.3 - 0.2 * w
    return StaticResult(omega=omega, w=w, outcome=outcome, message="", load_fraction=1.0, state=np.zeros(3),
                        x_j=0.1, y_j=y, eccentricity=math.hypot(0.1, y), attitude_deg=10.0, h_min=0.3, theta=theta,
                        z=z, pressure=p, foil=0.05 * w * np.clip(-np.sin(theta), 0, None), eigenvalues=ev,
                        residual=1e-12, iterations=4)


def curves() -> dict:
    return {omega: [static_result(w, omega) for w in (0.0, 0.5, 1.0)] for omega in (0.5, 1.0)}


def transient(accel: float) -> TransientResult:
    spr = 16
    omega = 0.5
    tau = np.arange(40 * spr + 1) * (2 * math.pi / omega) / spr
    ph = omega * tau
    rotor = np.stack([0.1 * np.cos(ph), -0.5 + 0.1 * np.sin(ph), 0 * ph, 0 * ph], axis=1)
    speed = omega + accel * tau
    return TransientResult(tau=tau, speed=speed, rotor=rotor, h_min=0.3 + 0 * tau, final_state=np.zeros(4),
                           outcome="completed", message="", omega0=omega, accel=accel, samples_per_rev=spr,
                           rotor_kind="jeffcott")


def spectrogram() -> Spectrogram:
    speed = np.linspace(0.3, 0.6, 12)
    order = np.linspace(0.0, 3.0, 31)
    amp = np.exp(-((order[None, :] - 1.0) ** 2) / 0.01) + 0.01 + 0 * speed[:, None]
    return Spectrogram(tau=speed, speed=speed, omega=order, amplitude=amp, order=order, order_amplitude=amp,
                       segment_revs=np.full(12, 12.0))


# name -> (call with the keywords ax=, path=, title=, number of panels)
CASES = {
    "bifurcation": (lambda **kw: pb.plot_bifurcation(cycles(), **kw), 2),
    "multipliers": (lambda **kw: pb.plot_multipliers(cycles(), **kw), 1),
    "equilibria": (lambda **kw: pb.plot_equilibria(equilibria(), **kw), 2),
    "energy": (lambda **kw: pb.plot_energy([("A", cycles(), energy(cycles()))], **kw), 1),
    "energy_two": (lambda **kw: pb.plot_energy({"A": (cycles(), energy(cycles())),
                                                "B": (cycles(0.1), energy(cycles(), 2.0))}, **kw), 2),
    "schedule": (lambda **kw: pb.plot_schedule([("a", schedule())], **kw), 6),
    "load_displacement": (lambda **kw: ps.plot_load_displacement(curves(), **kw), 1),
    "equilibrium_locus": (lambda **kw: ps.plot_equilibrium_locus(curves(), **kw), 3),
    "static_summary": (lambda **kw: ps.plot_static_summary(static_result(0.5), **kw), 6),
    "runup": (lambda **kw: pt.plot_runup(transient(1e-4), {"speed": np.array([0.5, 0.6]),
                                                            "y_max": np.array([-0.4, -0.3]),
                                                            "stable": np.array([True, False])}, **kw), 2),
    "spectrogram": (lambda **kw: pt.plot_spectrogram(spectrogram(), **kw), 1),
    "orbit_poincare_fft": (lambda **kw: pt.plot_orbit_poincare_fft(transient(0.0), last=20, **kw), 3),
}


def _panels(fig) -> list:
    return [a for a in fig.axes if a.get_visible() and a.get_label() != "<colorbar>"]


@pytest.mark.parametrize("name", CASES)
def test_draws_into_given_axes(name, tmp_path):
    call, n = CASES[name]
    fig, axes = plt.subplots(1, n, squeeze=False)
    out = call(ax=axes if n > 1 else axes[0, 0], path=tmp_path / "given.png")
    assert out is fig
    for a in axes.ravel():
        assert a.lines or a.get_title() == "(a) pressure field"  # that panel is a filled contour
        assert a.lines or a.collections
    assert fig._suptitle is None  # the caller's figure gets no default suptitle
    assert (tmp_path / "given.png").read_bytes()[:8] == PNG


@pytest.mark.parametrize("name", CASES)
def test_new_figure_saved_to_path(name, tmp_path):
    call, n = CASES[name]
    before = plt.get_fignums()
    path = tmp_path / "sub" / f"{name}.png"  # folders are made
    fig = call(path=path)
    assert fig.number not in before
    assert len(_panels(fig)) == n
    assert path.read_bytes()[:8] == PNG


@pytest.mark.parametrize("name", CASES)
def test_wrong_number_of_axes(name):
    call, n = CASES[name]
    fig, axes = plt.subplots(1, n + 1, squeeze=False)
    with pytest.raises(ValueError, match=rf"^ax: this figure has {n} panel"):
        call(ax=list(axes.ravel()))


def test_ax_must_be_axes():
    with pytest.raises(ValueError, match="^ax: .*other than Axes"):
        pb.plot_multipliers(cycles(), ax="not an axes")
    f1, a1 = plt.subplots()
    f2, a2 = plt.subplots()
    with pytest.raises(ValueError, match="^ax: .*one figure"):
        pb.plot_bifurcation(cycles(), ax=[a1, a2])


def test_given_axes_keep_an_explicit_title_and_a_2d_layout():
    fig, axes = plt.subplots(2, 3)
    ps.plot_static_summary(static_result(0.5), ax=axes, title="mine")
    assert fig._suptitle.get_text() == "mine"
    assert axes[0, 0].get_title() == "(a) pressure field"


# -- overlays ----------------------------------------------------------------------------------------------------


def _legend(ax) -> list[str]:
    return ax.get_legend_handles_labels()[1]


def _colours(ax, ls):
    return {matplotlib.colors.to_hex(l.get_color()) for l in ax.lines if l.get_linestyle() == ls and len(l.get_xdata())}


@pytest.mark.parametrize("several", [
    lambda: {"design A": cycles(), "design B": cycles(0.2)},
    lambda: [("design A", cycles()), ("design B", cycles(0.2))],
])
def test_bifurcation_overlay(several):
    fig = pb.plot_bifurcation(several())
    top = fig.axes[0]
    labels = _legend(top)
    assert {"design A", "design B", "stable", "unstable"} <= set(labels)
    assert {"NS", "PD (not located)", "flagged (accuracy or contact)"} <= set(labels)
    assert labels.count("NS") == 1  # one legend entry per special type, not per branch
    assert len(_colours(top, "-")) == 2 and _colours(top, "-") == _colours(top, "--")  # one colour each, both styles
    # special points: located filled, unlocated hollow; flagged points as grey crosses
    ns = [l for l in top.lines if l.get_marker() == "D"]
    pd = [l for l in top.lines if l.get_marker() == "s"]
    assert len(ns) == 4 and all(l.get_markerfacecolor() != "none" for l in ns)
    assert len(pd) == 4 and all(l.get_markerfacecolor() == "none" for l in pd)
    assert sum(l.get_marker() == "x" for l in top.lines) == 2


def test_single_branch_looks_as_before():
    fig = pb.plot_bifurcation(cycles())
    labels = _legend(fig.axes[0])
    assert labels[:4] == ["max (stable)", "max (unstable)", "min (stable)", "min (unstable)"]
    assert _colours(fig.axes[0], "-") == {"#d62728", "#1f77b4"}  # tab:red max, tab:blue min
    assert fig._suptitle.get_text() == "Limit cycles: bifurcation diagram"
    fig = pb.plot_multipliers(cycles())
    assert len(fig.axes) == 2  # with the speed colour bar


def test_multipliers_overlay():
    fig, ax = plt.subplots()
    pb.plot_multipliers({"A": cycles(), "B": cycles(0.1)}, ax=ax)
    labels = _legend(ax)
    assert "A" in labels and "B" in labels and "A: NS at 0.4000" in labels
    assert len(fig.axes) == 1  # no colour bar for an overlay


def test_equilibria_overlay():
    fig = pb.plot_equilibria([("rigid", equilibria()), ("soft", equilibria(0.05))])
    top, bottom = fig.axes
    assert {"rigid", "soft", "stable", "unstable"} <= set(_legend(top))
    assert {"rigid", "soft", "rigid: HOPF 0.2500", "soft: FOLD? 0.3800"} <= set(_legend(bottom))
    assert len(_colours(bottom, "-")) >= 2
    hopf = [l for l in top.lines if l.get_marker() == "*"]
    fold = [l for l in top.lines if l.get_marker() == "^"]
    assert hopf and all(l.get_markerfacecolor() != "none" for l in hopf)
    assert fold and all(l.get_markerfacecolor() == "none" for l in fold)


def test_energy_overlay_and_panels():
    b1, b2 = cycles(), cycles(0.1)
    fig = pb.plot_energy([("A", b1, energy(b1)), ("B", b2, energy(b2, 2.0))])
    assert [a.get_title() for a in fig.axes] == ["A", "B"]  # one panel per design, as before
    fig, ax = plt.subplots()
    assert pb.plot_energy({"A": (b1, energy(b1)), "B": (b2, energy(b2, 2.0))}, overlay=True, ax=ax) is fig
    assert {"A", "B", "stable", "unstable"} <= set(_legend(ax))
    fig = pb.plot_energy((b1, energy(b1)), quantities=["W_cb"])  # one design, one quantity
    assert len(fig.axes) == 1
    with pytest.raises(ValueError, match="quantities"):
        pb.plot_energy((b1, energy(b1)), quantities=["W_x"])


def test_bad_branch_collections():
    with pytest.raises(ValueError, match="empty"):
        pb.plot_bifurcation({})
    with pytest.raises(TypeError, match="label"):
        pb.plot_bifurcation([cycles(), cycles()])


@pytest.mark.parametrize("draw", [lambda b: pb.plot_bifurcation(b),
                                  lambda b: pb.plot_energy([("A", b, energy(b))])])
def test_special_point_labels_stay_inside_the_axes(draw):
    """A new user's report: the NS label at the right end of a branch was cut off by the axes' edge."""
    fig = draw(cycles(ns_row=8))  # as a branch run downwards in speed from just above its NS point
    fig.canvas.draw()
    labels = [t for a in fig.axes for t in a.texts if t.get_text().startswith("NS")]
    assert labels
    for t in labels:
        box, frame = t.get_window_extent(), t.axes.get_window_extent()
        assert frame.x0 <= box.x0 and box.x1 <= frame.x1, (t.get_text(), box, frame)
