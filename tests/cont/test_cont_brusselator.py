"""Hopf points of the discretised 1-D Brusselator against their closed form (and, when installed, AUTO-07p).

u_t = D_u/L^2 u_xx + A - (B+1) u + u^2 v,  v_t = D_v/L^2 v_xx + B u - u^2 v on [0, 1], u = A, v = B/A at both
ends, central differences on Nx interior points (h = 1/(Nx+1)), state (u_1, v_1, ..., u_Nx, v_Nx), parameter L.
The homogeneous state is an equilibrium for every L.  The discrete Dirichlet Laplacian has the eigenvalues
-k_j, k_j = (2 - 2 cos(j pi h)) / h^2, j = 1..Nx, with eigenvectors sin(j pi i h) shared by u and v, so the
Jacobian splits into the 2x2 blocks

    J_j = [[B - 1 - D_u k_j / L^2, A^2], [-B, -A^2 - D_v k_j / L^2]].

Mode j has a Hopf point where trace J_j = 0 with det J_j > 0:  L_j = sqrt((D_u + D_v) k_j / (B - 1 - A^2)), at
frequency omega_j = sqrt(det J_j).  With A = 2, B = 5.45, D_u = 0.008, D_v = 0.004 the determinant is positive
for every k, so continuing in increasing L from a small L meets the modes j = 1, 2, ... in that order.
"""
import importlib
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import EquilibriumProblem, EquilibriumSettings, continue_equilibria, hopf_point

A, B, DU, DV = 2.0, 5.45, 0.008, 0.004
L_START, L_END = 0.1, 1.1
BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


def _benchmark_module(name):
    """A module of benchmarks/ (the Brusselator of the AUTO comparison is the one tested here)."""
    saved = list(sys.path)
    sys.path.insert(0, str(BENCH))  # peer_auto imports _auto07p beside it
    try:
        return importlib.import_module(name)
    finally:
        sys.path[:] = saved


PEER = _benchmark_module("peer_auto")
brusselator = PEER.brusselator
assert (PEER.A, PEER.B, PEER.DU, PEER.DV) == (A, B, DU, DV)


P = jnp.array([A, B, DU, DV])


def laplacian_eigs(nx):
    h = 1.0 / (nx + 1)
    return (2.0 - 2.0 * np.cos(np.arange(1, nx + 1) * np.pi * h)) / h ** 2


def analytic_hopf(nx, j):
    """(L, omega) of the Hopf point of mode j (1-based), in closed form."""
    k = laplacian_eigs(nx)[j - 1]
    L = np.sqrt((DU + DV) * k / (B - 1.0 - A * A))
    du, dv = DU * k / L ** 2, DV * k / L ** 2
    assert abs((B - 1.0 - du) + (-A * A - dv)) < 1e-14  # the trace vanishes there
    det = (B - 1.0 - du) * (-A * A - dv) + B * A * A
    assert det > 0.0
    return L, np.sqrt(det)


def homogeneous(nx):
    return np.tile([A, B / A], nx)


@pytest.fixture(scope="module", params=[2, 5], ids=lambda nx: f"Nx={nx}")
def hopf_branch(request):
    nx = request.param
    prob = EquilibriumProblem(brusselator, 2 * nx, P)
    st = EquilibriumSettings(ds=0.02, ds_max=0.05, lam_max=L_END, max_points=200)
    return nx, prob, continue_equilibria(prob, st, homogeneous(nx), L_START)


def test_jacobian_is_the_block_spectrum():
    """The discretisation is the one the closed form describes: the eigenvalues of df/dx at the homogeneous
    state are those of the 2x2 blocks J_j, j = 1..Nx."""
    nx, L = 4, 0.7
    J = np.asarray(jax.jacfwd(lambda x: brusselator(x, L, P))(jnp.asarray(homogeneous(nx))))
    blocks = [np.array([[B - 1.0 - DU * k / L ** 2, A * A], [-B, -A * A - DV * k / L ** 2]])
              for k in laplacian_eigs(nx)]
    expect = np.sort_complex(np.concatenate([np.linalg.eigvals(b) for b in blocks]))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(J)), expect, rtol=0, atol=1e-11)
    np.testing.assert_allclose(np.asarray(brusselator(jnp.asarray(homogeneous(nx)), L, P)), 0.0, atol=1e-13)


def test_hopf_points_match_closed_form(hopf_branch):
    nx, prob, br = hopf_branch
    hs = br.special_of("HOPF")
    expected = [analytic_hopf(nx, j) for j in (1, 2)]
    assert all(e[0] < L_END for e in expected)
    assert len(hs) == 2, [(s.type, s.lam) for s in br.special]
    assert all(s.located for s in hs)
    for i, (L, omega) in enumerate(expected):
        hp = hopf_point(prob, br, i)
        assert abs(hp.lam - L) < 1e-8, (i, hp.lam, L)
        assert abs(hp.omega - omega) < 1e-8, (i, hp.omega, omega)
        assert abs(hs[i].period - 2 * np.pi / omega) < 1e-7
    # stable before the first Hopf point, one unstable pair between the two, two after the second
    n_unstable = np.sum(br.multipliers.real > 1e-9, axis=1)
    L1, L2 = expected[0][0], expected[1][0]
    assert np.all(n_unstable[br.lam < L1 - 1e-6] == 0)
    assert np.all(n_unstable[(br.lam > L1 + 1e-6) & (br.lam < L2 - 1e-6)] == 2)
    assert np.all(n_unstable[br.lam > L2 + 1e-6] == 4)


def test_hopf_point_matches_auto07p(tmp_path):
    """Optional: the same first Hopf point from AUTO-07p (Nx = 5), when AUTO-07p and gfortran are installed."""
    auto = _benchmark_module("_auto07p")
    inst, why = auto.locate()
    if inst is None:
        pytest.skip(why)
    peer = PEER
    nx = 5
    exe = inst.build(peer.fortran_source(), tmp_path, "brus")
    run = auto.run(exe, peer.auto_equilibrium_constants(2 * nx))
    hb = [r for r in run.rows if r["type"] == "HB"]
    assert run.returncode == 0 and hb, run.stdout + run.stderr
    prob = EquilibriumProblem(brusselator, 2 * nx, P)
    br = continue_equilibria(prob, EquilibriumSettings(ds=0.02, ds_max=0.05, lam_max=peer.EQ_END, max_points=200),
                             homogeneous(nx), L_START)
    L_auto = hb[0]["PAR(5)"]  # AUTO prints 11 significant digits
    assert abs(hopf_point(prob, br).lam - L_auto) < 1e-8
    assert abs(L_auto - analytic_hopf(nx, 1)[0]) < 1e-8


#: Branch points and tori of the symmetric cycles (Nx = 10, N = 20, m = 4, fixed mesh) up to L = 3.3, from
#: AUTO-07p 0.9.2 on the same discretisation (benchmarks/peer_auto.py; AUTO prints BP at L = 1.23784 and 1.87257,
#: TR at 2.57737 and 3.13660, and reports no torus between its branch points).
AUTO_BPC_NX10 = (1.23784, 1.87257)
AUTO_TR_NX10 = (2.57737, 3.13660)
#: The same branch points from AUTO-07p with tight tolerances (EPSL = EPSU = 1e-8, EPSS = 1e-6; the constants of
#: peer_auto.auto_cycle_constants with eps = 1e-8), from its b-file: they move by ~1e-8 between eps = 3e-8 and 1e-8.
AUTO_BPC_NX10_TIGHT = (1.2378346494, 1.8725667311)


def test_cycle_branch_passes_its_branch_points_and_finds_every_torus():
    """The cycle branch from the first Hopf point, with both linear solvers: it passes both symmetry-breaking branch
    points of cycles and reports each (not located: the corrections that would locate a branch point are singular
    next to it), and between them two complex pairs leave the unit circle (two NS, while a real multiplier is
    already outside).  Before, the halved steps crept towards a branch point until ds < ds_min and the branch
    ended there; and with steps that cover both tori the NS test changed sign twice and reported neither (AUTO-07p
    reports neither either).  Past L = 2.5 two more pairs leave and two more enter the circle (AUTO's two TR
    among them) while up to eleven multipliers lie at or outside it: with the sparse solver's partial spectrum (the
    leading multipliers by Arnoldi) the crossing pair at 3.1366 was the last computed, its conjugate cut off, and
    it was read as a real multiplier at +1 (a false BPC).  The two solvers compute the multipliers differently
    (all of them by periodic QR; the leading ones by Arnoldi on sweeps): they must agree on every torus."""
    from gfbjax import cont

    nx = 10
    ep = EquilibriumProblem(brusselator, 2 * nx, P)
    eb = continue_equilibria(ep, EquilibriumSettings(ds=0.02, ds_max=0.05, lam_max=0.7, max_points=200),
                             homogeneous(nx), L_START)
    hopf = hopf_point(ep, eb)
    prob = cont.CycleProblem(brusselator, 2 * nx, P, jac_sparsity=PEER.pattern(nx))
    ns = {}
    for solver in (cont.DenseCondensation(), cont.SparseSweep()):
        st = cont.CycleSettings(m=4, N=20, adapt=0, ds=0.01, ds_max=0.2, ds_min=1e-6, max_points=200, lam_max=3.3,
                                linear_solver=solver)
        br = cont.continue_cycles(prob, st, cont.start_from_hopf(hopf, st))
        assert br.outcome == cont.Outcome.REACHED_END, br.message
        assert [s.type for s in br.special] == ["BPC", "NS", "NS", "BPC", "NS", "NS", "NS", "NS"], br.special
        # an unlocated branch point is reported at a point of its last step: AUTO's value lies between the rows
        # around it (to AUTO's printed precision)
        for s, L_auto in zip([s for s in br.special if s.type == "BPC"], AUTO_BPC_NX10):
            around = br.lam[max(s.index - 1, 0): s.index + 2]
            assert around.min() - 1e-5 <= L_auto <= around.max() + 1e-5, (L_auto, around)
            # the reported error (the bracket's width where the corrections failed) covers AUTO's value
            assert abs(s.lam - L_auto) <= s.lam_error + 1e-5, (s.lam, s.lam_error, L_auto)
        for s, L_tight in zip([s for s in br.special if s.type == "BPC"], AUTO_BPC_NX10_TIGHT):
            # The dense solver also places each across the gap where corrections fail, by the regular bordered
            # test (_localise._across_the_gap): 1.3e-7 and 2.9e-7 from AUTO's tight values (the two tools' meshes
            # and phase conditions differ at that level), where the multiplier test alone was 2e-6 off.  The
            # sparse solver's GMRES does not converge for that test next to the branch point: its noise-widened
            # bracket (up to 7.5e-5) must cover AUTO's value instead.
            tol = 5e-7 if solver.name == "dense" else s.lam_error + 5e-7
            assert abs(s.lam - L_tight) <= tol, (solver.name, s.lam, s.lam_error, L_tight)
        ns[solver.name] = [s for s in br.special if s.type == "NS"]
        for s in ns[solver.name]:
            assert s.located
            on_circle = np.min(np.abs(np.abs(s.spectrum[np.abs(s.spectrum.imag) > 1e-3]) - 1.0))
            # a complex pair on the unit circle: the located test function (< 1e-9) is this distance times the next
            # smallest factor, which is itself small here (down to ~1e-4 with up to eleven multipliers at or
            # outside the circle); AUTO prints its multipliers to 1e-5
            assert on_circle < 1e-5
    # both located to |test| < 1e-9; past L = 3, with up to eleven multipliers at or outside the circle, the test
    # function is flat (the product of its two smallest factors, both small), and the two solvers' multipliers
    # (periodic QR against Arnoldi and GMRES to 1e-11) move its zero by up to a few 1e-6 in L: agreement is
    # asserted to AUTO's printed precision
    np.testing.assert_allclose([s.lam for s in ns["dense"]], [s.lam for s in ns["sparse"]], atol=1e-5)
    for L_auto in AUTO_TR_NX10:  # AUTO's tori, to its printed precision
        assert min(abs(s.lam - L_auto) for s in ns["dense"]) < 1e-5, L_auto
