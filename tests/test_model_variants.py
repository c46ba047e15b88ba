"""Model variants of the paper's validation case (Table 1): the SystemSpec options ``gumbel``, ``foil_springs`` and
``axial_domain``, and the rotor mass of ``validation_case(..., mass_per_bearing=...)``.

Each variant is checked against an answer that does not come from the code: the mirror symmetry of an aligned
journal's film, the sign of a film clipped at ambient, the paper's spring count (Sect. 2.1), Newton's laws for
the static load, and the paper's Table 1 itself.  Grids are 16x2 (a continuation there takes a few seconds).
"""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax import ParameterError, SystemSpec, validation_case
from gfbjax.analyses.cycles import branch_meta, continue_gfb_equilibria
from gfbjax.analyses.static import solve_equilibrium
from gfbjax.model import bearing_force, core_rates, foil_drive, layout, mean_gauge_pressure
from gfbjax.model import foil as foil_module
from gfbjax.model import reynolds
from gfbjax.params import AXIAL_DOMAINS, FOIL_SPRINGS, GUMBEL

TINY = dict(Nx=16, Nz=2)
OMEGA = 0.6  # near the validation case's Hopf point (Omega_bar 0.60 = 13,800 rpm)
PAPER_RPM = 12030.0  # Table 1 / Fig. 6c, 10 N per bearing, as the paper reports it
OPTIONS = ("gumbel", "foil_springs", "axial_domain")


def _hopf_rpm(spec):
    b = continue_gfb_equilibria(spec.nondim(), 0.25, 1.5, spec=spec)
    hp = b.special_of("HOPF")
    assert hp, f"no Hopf point for {spec}"
    return spec.rpm(float(hp[0].lam))


@pytest.fixture(scope="module")
def base():
    return validation_case(10.0, **TINY)


@pytest.fixture(scope="module")
def base_eq(base):
    eq = solve_equilibrium(base.nondim(), OMEGA)
    assert eq.converged
    return eq


@pytest.fixture(scope="module")
def base_hopf(base):
    return _hopf_rpm(base)


# -- validation, defaults and records ---------------------------------------------------------------------------

@pytest.mark.parametrize("field, bad", [("gumbel", "film"), ("gumbel", None), ("foil_springs", "none"),
                                        ("foil_springs", 2), ("axial_domain", "quarter"), ("axial_domain", "")])
def test_bad_option_raises_naming_field_and_allowed_values(field, bad):
    allowed = {"gumbel": GUMBEL, "foil_springs": FOIL_SPRINGS, "axial_domain": AXIAL_DOMAINS}[field]
    with pytest.raises(ParameterError, match=rf"^{field} = .* is not one of") as exc:
        SystemSpec(**{field: bad})
    assert all(v in str(exc.value) for v in allowed)
    with pytest.raises(ParameterError, match=field):
        validation_case(10.0, **{field: bad})
    # hand-made Params are checked at an analysis' entry as a SystemSpec is
    params = dataclasses.replace(SystemSpec(**TINY).nondim(), **{field: bad})
    with pytest.raises(ParameterError, match=field):
        params.check()


def test_option_tuples_agree_between_spec_and_model():
    assert GUMBEL == reynolds.GUMBEL
    assert FOIL_SPRINGS == foil_module.FOIL_SPRINGS
    with pytest.raises(ParameterError, match="foil_springs"):
        foil_module.supported_drive(jnp.ones(3), "some")


def test_full_length_counts_in_the_state_bound():
    # (Nx - 1)(Nz + 1) + 8 = 399 * 9 + 8 = 3599 states on the half length, 399 * 16 + 8 = 6392 > 6144 on the full
    assert SystemSpec(Nx=400, Nz=8).nondim().Nx == 400
    with pytest.raises(ParameterError, match="6392 states"):
        SystemSpec(Nx=400, Nz=8, axial_domain="full")


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, "heavy"])
def test_bad_mass_per_bearing_raises_naming_it(bad):
    with pytest.raises(ParameterError, match="mass_per_bearing"):
        validation_case(10.0, mass_per_bearing=bad)


def test_defaults_are_the_model_before_the_options():
    spec = SystemSpec()
    assert (spec.gumbel, spec.foil_springs, spec.axial_domain) == ("forces", "all", "half")
    p = validation_case(10.0).nondim()
    assert (p.gumbel, p.foil_springs, p.axial_domain) == ("forces", "all", "half")
    assert validation_case(10.0).m_j == pytest.approx(10.0 / 9.81, rel=1e-15) and validation_case(10.0).load == 0.0
    # a result file written before the options existed lacks their keys and reads back as the same system
    old = {k: v for k, v in validation_case(10.0).to_dict().items() if k not in OPTIONS}
    assert SystemSpec(**old) == validation_case(10.0)
    # the options are model choices, not conventions: the presets leave them alone and ignore them
    assert validation_case(10.0, preset="paper").gumbel == "forces"
    assert validation_case(10.0, gumbel="pressure", axial_domain="full").preset == "corrected"


def test_default_hopf_speed_unchanged(base_hopf):
    # docs/reproduction.md, measured before the options existed: 13,995 rpm on 16x2 (rounded to the rpm)
    assert base_hopf == pytest.approx(13995.0, abs=0.5)


def test_options_are_recorded_in_outputs():
    spec = validation_case(10.0, gumbel="pressure", foil_springs="no_first", axial_domain="full", **TINY)
    d = spec.to_dict()
    assert (d["gumbel"], d["foil_springs"], d["axial_domain"]) == ("pressure", "no_first", "full")
    meta = branch_meta(spec.nondim(), "equilibria", spec)
    assert meta["spec"]["axial_domain"] == "full" and meta["params"]["gumbel"] == "pressure"
    assert meta["params"]["foil_springs"] == "no_first" and "model_options" in meta["conventions"]
    # 15 circumferential unknowns times 2 Nz - 1 = 3 axial ones
    assert meta["grid"]["n_pressure"] == 15 * 3


# -- (d) full axial domain ------------------------------------------------------------------------------------------

def test_full_length_is_the_mirrored_half_domain(base, base_eq, base_hopf):
    """An aligned journal's film is symmetric about the mid-plane, p(z) = p(1 - z).  At the same spacing the full
    grid's symmetric solution solves the half domain's equations node for node (the half domain's mirror node is
    the other half's node), so the two agree to the Newton tolerance, not to a discretisation error."""
    full = base.replace(axial_domain="full")
    eq = solve_equilibrium(full.nondim(), OMEGA)
    assert eq.converged
    assert eq.state.size == 15 * 3 + 15 + 4
    P = eq.pressure
    assert P.shape == (17, 5) and eq.z[0] == 0.0 and eq.z[-1] == pytest.approx(1.0)
    np.testing.assert_allclose(P, P[:, ::-1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(P[:, :3], base_eq.pressure, rtol=0, atol=1e-9)
    assert (eq.x_j, eq.y_j) == pytest.approx((base_eq.x_j, base_eq.y_j), abs=1e-9)
    # the critical (rightmost) eigenvalue is a symmetric mode: the half domain's
    assert eq.eigenvalues[0] == pytest.approx(base_eq.eigenvalues[0], abs=1e-8)
    assert _hopf_rpm(full) == pytest.approx(base_hopf, rel=1e-7)


# -- (a) Gumbel condition on the film pressure ----------------------------------------------------------------------

def test_clipped_film_stays_at_or_above_ambient(base, base_eq):
    """The film clipped at ambient (``gumbel="pressure"``) never goes below it, and above it satisfies the Reynolds
    equation; where it is held at ambient the Reynolds equation would pull it lower."""
    assert base_eq.pressure.min() < 0.99  # the default film has a sub-ambient region to clip
    clip = base.replace(gumbel="pressure")
    eq = solve_equilibrium(clip.nondim(), OMEGA)
    assert eq.converged
    assert eq.pressure.min() >= 1.0 - 1e-10
    p = base.nondim()
    lay = layout(p)
    reyn = np.asarray(core_rates(jnp.asarray(eq.state), jnp.asarray(OMEGA), jnp.zeros(2), p)[: lay.grid.n_pressure])
    Pu = np.asarray(lay.pressures(jnp.asarray(eq.state))).ravel()
    free, held = Pu > 1.0 + 1e-7, Pu < 1.0 + 1e-9
    assert held.sum() > 0 and free.sum() > 0
    assert np.abs(reyn[free]).max() < 1e-8
    assert reyn[held].max() < 1e-9
    # the bearing carries the rotor's weight, 10 N, whichever way the film is modelled (Newton's first law)
    F = bearing_force(lay.pressures(jnp.asarray(eq.state)), lay.grid.theta(p.theta0), lay.grid)
    assert float(F[1]) * base.force_scale == pytest.approx(10.0, rel=1e-8)
    assert abs(float(F[0])) * base.force_scale < 1e-8


# -- (b) spring count --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("springs, held", [("all", None), ("no_first", 0), ("no_last", -1)])
def test_spring_count_of_the_paper(springs, held):
    """Sect. 2.1: ``N_X - 2`` springs under ``N_X - 1`` strips; the strip without one does not feel the film."""
    p = validation_case(10.0, foil_springs=springs, **TINY).nondim()
    lay = layout(p)
    n_strips = TINY["Nx"] - 1
    # every film node above ambient, so every sprung strip is loaded
    s = jnp.concatenate([jnp.full(lay.grid.n_pressure, 1.3), jnp.full(n_strips, 0.01), jnp.zeros(4)])
    J = np.asarray(jax.jacfwd(core_rates)(s, jnp.asarray(OMEGA), jnp.zeros(2), p))
    coupled = np.any(J[lay.slices["foil"], lay.slices["pressures"]] != 0, axis=1)
    assert coupled.sum() == (n_strips if held is None else n_strips - 1)
    # the total spring force under a uniform unit load is k_f times the deflection summed: one per sprung strip
    drive = foil_drive(lay.pressures(s), lay.grid, p)
    assert float(jnp.sum(drive > 0)) == coupled.sum()
    if held is not None:
        assert not coupled[held] and coupled[held + 1 if held == 0 else held - 1]
        # held at the housing: from any deflection it relaxes to q = 0
        qdot = np.asarray(core_rates(s, jnp.asarray(OMEGA), jnp.zeros(2), p)[lay.slices["foil"]])
        assert qdot[held] < 0.0


def test_end_strips_of_the_validation_case_carry_no_load(base, base_eq):
    """The strips next to the fixed end (theta0 = 90 deg, the unloaded top of the bearing) see a sub-ambient film,
    so the Gumbel condition already leaves them unloaded: holding either one changes nothing."""
    p = base.nondim()
    lay = layout(p)
    pm = np.asarray(mean_gauge_pressure(lay.pressures(jnp.asarray(base_eq.state)), lay.grid))
    assert pm[0] < 0 and pm[-1] < 0
    for springs in ("no_first", "no_last"):
        eq = solve_equilibrium(base.replace(foil_springs=springs).nondim(), OMEGA)
        np.testing.assert_allclose(eq.state, base_eq.state, rtol=0, atol=1e-10)


# -- (c) rotor mass under the same static load ------------------------------------------------------------------

def test_mass_changes_the_dynamics_not_the_statics(base, base_eq, base_hopf):
    """Statics do not see inertia: under the same 10 N every rotor mass has the same equilibrium, and the bearing
    carries 10 N.  With ``m = load / g`` the external force is the weight itself (same Hopf speed).  A heavier
    rotor whirls at a lower speed (the critical mass of a gas bearing falls with speed): the Hopf speed falls."""
    heavy = validation_case(10.0, mass_per_bearing=2.0, **TINY)
    assert heavy.m_j == 2.0 and heavy.g == 0.0 and heavy.load == 10.0
    eq = solve_equilibrium(heavy.nondim(), OMEGA)
    assert eq.converged
    assert (eq.x_j, eq.y_j) == pytest.approx((base_eq.x_j, base_eq.y_j), abs=1e-9)
    lay = layout(heavy.nondim())
    F = bearing_force(lay.pressures(jnp.asarray(eq.state)), lay.grid.theta(heavy.theta0), lay.grid)
    assert float(F[1]) * heavy.force_scale == pytest.approx(10.0, rel=1e-8)
    same = _hopf_rpm(validation_case(10.0, mass_per_bearing=10.0 / 9.81, **TINY))
    assert same == pytest.approx(base_hopf, rel=1e-7)
    light = _hopf_rpm(validation_case(10.0, mass_per_bearing=0.75, **TINY))
    assert _hopf_rpm(heavy) < base_hopf < light


# -- the paper's Table 1 --------------------------------------------------------------------------------------------

def test_table1_hopf_speed_against_the_paper(base_hopf):
    """Table 1 / Fig. 6c: 12,030 rpm for 10 N per bearing (Zhou et al., as the paper reports them: 11,475 rpm).

    Tolerance 20 %.  The paper gives no rotor mass, and the Hopf speed goes roughly as ``m^-0.4`` (measured by
    benchmarks/table1_variants.py: 0.5 to 3 kg per bearing moves it from +55 % to -24 %).  Read as the rotor's
    weight, the text's 10 N gives +14.7 % (default grid); Table 1's 15 N read as the weight with the text's 10 N
    as the load gives -2.8 %.  The paper's grid is unreported (gfbjax's grids from 16x2 to 80x8 spread 2 %), and
    the paper and Zhou et al. differ by 4.6 % between themselves.  So the comparison bounds the model, it cannot
    pin it: the baseline must lie within 20 % (+14.7 % measured, +16.3 % on this grid), and the paper's value
    must lie between the two mass readings.
    """
    assert abs(base_hopf / PAPER_RPM - 1.0) < 0.20
    weight15 = _hopf_rpm(validation_case(10.0, mass_per_bearing=15.0 / 9.81, **TINY))
    assert weight15 < PAPER_RPM < base_hopf


def test_pressure_gumbel_leaves_the_reynolds_rates_above_ambient():
    """Above ambient the Reynolds rates pass unchanged (a film may fall as fast as the Reynolds equation says);
    at ambient a negative rate is held at 0, below it the node returns at rate (1 - p).  Before, a falling pressure
    above ambient was capped at (p - 1) per tau: p = 1.05, 1.5 with rates -0.5, -2.0 came out as -0.05, -0.5
    (review of this issue)."""
    import jax.numpy as jnp

    from gfbjax.model.reynolds import ambient_clipped_rates

    P = jnp.array([1.05, 1.5, 1.0, 0.8, 0.8])
    Pdot = jnp.array([-0.5, -2.0, -0.3, -1.0, 0.5])
    np.testing.assert_allclose(ambient_clipped_rates(Pdot, P), [-0.5, -2.0, 0.0, 0.2, 0.5], atol=1e-15)
