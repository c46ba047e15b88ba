"""The convention switches of SystemSpec (foil damping, unbalance mass, unit of omega_r) and the presets
"corrected" / "paper" (docs/model.md), against values worked out by hand."""

import math
import warnings

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import gfbjax
from gfbjax import ParameterError, SystemSpec, reference_system, unbalance_eccentricity, variation
from gfbjax.analyses.cycles import branch_meta
from gfbjax.analyses.energy import power
from gfbjax.model import layout, vector_field
from gfbjax.model.foil import foil_damping_coefficient, foil_rates
from gfbjax.params import PRESETS, load_config

TINY = dict(Nx=16, Nz=2)


# -- Omega_r unit (Eq. 16) -------------------------------------------------------------------------------------

def test_unbalance_eccentricity_units_by_hand():
    # 2500 rpm = 2500 * 2 pi / 60 = 261.799 rad/s; G6.3: 6.3e-3 / 261.799 = 24.064e-6 m (the paper's 24.1 um),
    # G2.5: 9.549e-6 m (the paper's 9.55 um); in rad/s G2.5 gives 2.5e-3 / 2500 = 1.0e-6 m.
    assert unbalance_eccentricity(6.3, 2500.0, "rpm") == pytest.approx(24.064e-6, rel=1e-4)
    assert round(unbalance_eccentricity(6.3, 2500.0, "rpm") * 1e6, 1) == 24.1
    assert round(unbalance_eccentricity(2.5, 2500.0, "rpm") * 1e6, 2) == 9.55
    assert unbalance_eccentricity(2.5, 2500.0) == pytest.approx(1.0e-6, rel=1e-12)
    assert unbalance_eccentricity(2.5, 2500.0, "rad/s") == pytest.approx(1.0e-6, rel=1e-12)
    with pytest.raises(ParameterError, match="omega_r_unit"):
        unbalance_eccentricity(2.5, 2500.0, "Hz")
    assert SystemSpec(omega_r_unit="rpm").eccentricity_u == pytest.approx(24.064e-6, rel=1e-4)
    assert SystemSpec(omega_r_unit="rpm", e_u=3e-6).eccentricity_u == 3e-6  # e_u given: the unit is moot


# -- unbalance mass (Eq. 15a vs the text) ------------------------------------------------------------------------

def test_unbalance_mass_factor_by_hand():
    # reference: m_d = 1 kg, m_j = 0.5 kg per journal -> (m_d + 2 m_j) / m_d = 2
    disc, rotor = SystemSpec(), SystemSpec(unbalance_mass="rotor")
    assert disc.unbalance_factor == 1.0 and rotor.unbalance_factor == 2.0
    assert float(rotor.nondim().eps) == pytest.approx(2 * 2.52 / 38.1, rel=1e-12)
    # m_d = 3 kg, m_j = 0.25 kg: (3 + 0.5) / 3
    assert SystemSpec(m_d=3.0, m_j=0.25, unbalance_mass="rotor").unbalance_factor == pytest.approx(3.5 / 3)
    # the rigid rotor has no disc: unaffected
    rig = SystemSpec(rotor="rigid", unbalance_mass="rotor")
    assert rig.unbalance_factor == 1.0 and float(rig.nondim().eps) == pytest.approx(2.52 / 38.1, rel=1e-12)
    # the paper preset on the reference system: eps = 2 * 24.064 / 38.1 = 1.2632
    assert float(reference_system(preset="paper").nondim().eps) == pytest.approx(2 * 24.064 / 38.1, rel=1e-4)


def test_unbalance_force_ratio_in_vector_field():
    """The disc's acceleration from the unbalance, vector field with minus without unbalance: ratio 2."""
    accel = {}
    for mode in ("disc", "rotor"):
        params = SystemSpec(unbalance_mass=mode, **TINY).nondim()
        lay = layout(params, oscillator=True)
        s = np.full(lay.n, 0.0)
        s[: lay.grid.n_pressure] = 1.2
        s[-2:] = [math.cos(0.3), math.sin(0.3)]
        s = jnp.asarray(s)
        zero = eqx.tree_at(lambda p: p.eps, params, jnp.asarray(0.0))
        d = np.asarray(vector_field(s, 0.4, params) - vector_field(s, 0.4, zero))
        rot = lay.slices["rotor"]
        accel[mode] = d[rot][6:8]  # x_d'', y_d''
    # by hand: eps Omega^2 (cos 0.3, sin 0.3) with eps = 2.52/38.1 (disc) or twice that (rotor)
    eps = 2.52 / 38.1
    np.testing.assert_allclose(accel["disc"], eps * 0.16 * np.array([math.cos(0.3), math.sin(0.3)]), rtol=1e-12)
    np.testing.assert_allclose(accel["rotor"] / accel["disc"], [2.0, 2.0], rtol=1e-12)


# -- foil damping (Eq. 10) ---------------------------------------------------------------------------------------

def test_foil_damping_coefficient_by_hand():
    # eta = 0.05, alpha_f = 0.1 (k_f = 10), Omega_bar = 0.4: structural 0.05 * 10 / 0.4 = 1.25, paper 0.05 * 10 = 0.5
    assert float(foil_damping_coefficient(0.4, 0.1, 0.05)) == pytest.approx(1.25, rel=1e-14)
    assert float(foil_damping_coefficient(0.4, 0.1, 0.05, "paper")) == pytest.approx(0.5, rel=1e-14)
    # q' = (drive - k_f q) / c_f with drive 2, q 0.1: (2 - 1) / 1.25 = 0.8 and (2 - 1) / 0.5 = 2
    assert float(foil_rates(jnp.asarray(0.1), jnp.asarray(2.0), 0.4, 0.1, 0.05)) == pytest.approx(0.8, rel=1e-14)
    assert float(foil_rates(jnp.asarray(0.1), jnp.asarray(2.0), 0.4, 0.1, 0.05, "paper")) == pytest.approx(2.0)
    assert float(foil_rates(jnp.asarray(0.1), jnp.asarray(2.0), 0.4, 0.1, 0.05, 0.0)) == pytest.approx(2.0)
    assert float(foil_damping_coefficient(0.4, 0.1, 0.05, 1.0)) == pytest.approx(1.25, rel=1e-14)
    with pytest.raises(ParameterError, match="foil_damping"):
        foil_damping_coefficient(0.4, 0.1, 0.05, "viscous")


def _random_state(params, seed=0):
    lay = layout(params, oscillator=True)
    rng = np.random.default_rng(seed)
    s = np.concatenate([rng.uniform(1.1, 1.8, lay.grid.n_pressure), rng.uniform(0.0, 0.1, lay.n_foil),
                        rng.uniform(-0.2, 0.2, lay.n_rotor), [1.0, 0.0]])
    return lay, jnp.asarray(s)


def test_foil_damping_in_vector_field_and_energy():
    """Same state, both conventions: the strips move 1/Omega_bar faster with c_f = eta k_f (c_f is Omega_bar times
    smaller), and the foil's dissipated power c_f q'^2 is 1/Omega_bar times larger; nothing else changes."""
    om = 0.4
    ps = SystemSpec(**TINY).nondim()
    pp = SystemSpec(foil_damping="paper", **TINY).nondim()
    assert float(ps.structural_damping) == 1.0 and float(pp.structural_damping) == 0.0
    # the convention is a traced number, not part of the tree structure: switching it does not recompile
    import jax
    assert jax.tree_util.tree_structure(ps) == jax.tree_util.tree_structure(pp)
    lay, s = _random_state(ps)
    fs, fp = np.asarray(vector_field(s, om, ps)), np.asarray(vector_field(s, om, pp))
    foil = lay.slices["foil"]
    assert np.max(np.abs(fs[foil])) > 0.1
    np.testing.assert_allclose(fp[foil], fs[foil] / om, rtol=1e-12)
    rest = np.ones(lay.n, bool)
    rest[foil] = False
    rest[: lay.grid.n_pressure] = False  # pressures see q' through h'
    np.testing.assert_array_equal(fp[rest], fs[rest])
    P_s, P_p = np.asarray(power(s, om, ps)), np.asarray(power(s, om, pp))
    assert P_p[2] == pytest.approx(P_s[2] / om, rel=1e-12)
    np.testing.assert_allclose(P_p[:2], P_s[:2], rtol=1e-14)


# -- presets, checks, records --------------------------------------------------------------------------------

def test_presets():
    assert reference_system().preset == "corrected" and SystemSpec().preset == "corrected"
    paper = reference_system(preset="paper")
    assert (paper.foil_damping, paper.unbalance_mass, paper.omega_r_unit) == ("paper", "rotor", "rpm")
    assert paper.preset == "paper"
    assert paper.replace(foil_damping="structural").preset == "mixed"
    assert reference_system(preset="paper", foil_damping="structural").foil_damping == "structural"  # override
    assert variation("af1", preset="paper").alpha_f == 1.0
    assert gfbjax.validation_case(15.0, preset="paper").foil_damping == "paper"
    assert variation("validation10N", preset="paper").preset == "paper"
    assert SystemSpec().with_preset("paper") == paper
    assert paper.with_preset("corrected") == SystemSpec()
    assert set(PRESETS) == {"corrected", "paper"}
    for bad in ("literal", None, 3):
        with pytest.raises(ParameterError, match="preset"):
            SystemSpec().with_preset(bad)
    with pytest.raises(ParameterError, match="preset"):
        reference_system(preset="literal")


@pytest.mark.parametrize("field, value", [("foil_damping", "viscous"), ("unbalance_mass", "journal"),
                                          ("omega_r_unit", "rad")])
def test_bad_switch_names_the_field_and_choices(field, value):
    with pytest.raises(ParameterError, match=rf"{field} = .*{value}.* is not one of"):
        SystemSpec(**{field: value})


def test_eccentricity_above_clearance_warns_not_refuses():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        SystemSpec()  # 2.52 um < c: silent
        SystemSpec(omega_r_unit="rpm")  # 24.1 um < 38.1 um: silent
    with pytest.warns(UserWarning, match="e_u = 50 um exceeds the radial clearance"):
        spec = SystemSpec(e_u=50e-6)
    assert float(spec.nondim().check().eps) == pytest.approx(50 / 38.1)
    with pytest.warns(UserWarning, match="exceeds the radial clearance"):
        SystemSpec(G=40.0, omega_r_unit="rpm")  # 40e-3 / 261.8 = 152.8 um


def test_params_check_structural_damping():
    bad = eqx.tree_at(lambda p: p.structural_damping, SystemSpec(**TINY).nondim(), jnp.asarray(2.0))
    with pytest.raises(ParameterError, match=r"Params\.structural_damping"):
        bad.check()


def test_switches_recorded_in_branch_meta():
    spec = reference_system(preset="paper", **TINY)
    meta = branch_meta(spec.nondim(), "unbalance_response", spec)
    assert meta["preset"] == "paper"
    assert meta["spec"]["foil_damping"] == "paper" and meta["spec"]["unbalance_mass"] == "rotor"
    assert meta["spec"]["omega_r_unit"] == "rpm"
    assert meta["params"]["structural_damping"] == 0.0
    assert meta["params"]["eps"] == pytest.approx(2 * 24.064 / 38.1, rel=1e-4)
    assert "foil_damping" in meta["conventions"]
    # a corrected spec does not describe paper params
    with pytest.raises(ParameterError, match="spec does not describe params"):
        branch_meta(spec.nondim(), "unbalance_response", reference_system(**TINY))


def test_toml_preset(tmp_path):
    f = tmp_path / "sys.toml"
    f.write_text('base = "af1"\npreset = "paper"\neta = 0.2\n')
    spec = load_config(f)
    assert spec.preset == "paper" and spec.alpha_f == 1.0 and spec.eta == 0.2
    f.write_text('preset = "nonsense"\n')
    with pytest.raises(ParameterError, match="preset"):
        load_config(f)


def test_cli_preset_option():
    import argparse

    from gfbjax.cli.commands._common import add_system_options, spec_from_args

    parser = argparse.ArgumentParser()
    add_system_options(parser, "x")
    assert spec_from_args(parser.parse_args([])).preset == "corrected"
    spec = spec_from_args(parser.parse_args(["--preset", "paper", "--system", "G2.5"]))
    assert spec.preset == "paper" and spec.eccentricity_u == pytest.approx(9.549e-6, rel=1e-3)
    # --set applies after the preset
    spec = spec_from_args(parser.parse_args(["--preset", "paper", "--set", "omega_r_unit=rad/s"]))
    assert spec.omega_r_unit == "rad/s" and spec.foil_damping == "paper"
    with pytest.raises(SystemExit):
        parser.parse_args(["--preset", "literal"])


def test_runup_overlay_compares_unbalance_with_its_unit():
    from gfbjax.cli.commands.runup import _eccentricity

    assert _eccentricity({"G": 6.3, "omega_r": 2500.0, "omega_r_unit": "rpm"}) == pytest.approx(24.064e-6, rel=1e-4)
    assert _eccentricity({"G": 6.3, "omega_r": 2500.0}) == pytest.approx(2.52e-6, rel=1e-12)
