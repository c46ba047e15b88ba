"""SI inputs and dimensionless groups (gfbjax.params): range checks, config files, hand-computed values."""

import math

import pytest

import gfbjax
from gfbjax import (ParameterError, SystemSpec, bump_foil_compliance, load_config, reference_system,
                    system_from_name_or_file, unbalance_eccentricity, validation_case, variation)

NAN = float("nan")


@pytest.mark.parametrize("field, value", [
    ("R", 0.0), ("R", -0.01), ("R", NAN),
    ("L", 0.0), ("L", -1.0), ("L", float("inf")),
    ("c", 0.0), ("c", -1e-6), ("c", 0.1 * 19.05e-3),  # a clearance of 10 % of R is no foil bearing
    ("mu", 0.0), ("mu", NAN),
    ("p0", 0.0), ("p0", -1e5),
    ("g", -9.81),
    ("m_j", 0.0), ("m_j", -0.5), ("m_j", NAN),
    ("m_d", 0.0), ("m_d", -1.0),
    ("k_s_bar", 0.0), ("k_s_bar", -1.0),
    ("alpha_f", 0.0), ("alpha_f", -0.1), ("alpha_f", NAN),
    ("eta", -0.01), ("eta", NAN),
    ("G", -1.0), ("G", 1000.0),
    ("e_u", -1e-6), ("e_u", NAN),  # (e_u above the clearance is allowed with a warning: tests/test_conventions.py)
    ("foil_damping", "viscous"), ("unbalance_mass", "journal"), ("omega_r_unit", "Hz"),
    ("omega_r", 0.0),
    ("theta0", 10.0),
    ("load", -1.0),
    ("Nx", 8), ("Nx", 40.0), ("Nx", 5000),
    ("Nz", 1), ("Nz", 0), ("Nz", 6.5),
    ("gumbel_width", -0.01), ("gumbel_width", 1.0),
    ("rotor", "rigidish"),
])
def test_every_field_checked(field, value):
    with pytest.raises(ParameterError, match=rf"\b{field}\b"):
        SystemSpec(**{field: value})
    # the same check guards replace() and the named systems
    with pytest.raises(ParameterError, match=rf"\b{field}\b"):
        reference_system().replace(**{field: value})


def test_accepted_edges():
    assert SystemSpec(g=0.0).nondim().sigma == 0.0  # vertical rotor
    assert SystemSpec(rotor="rigid", m_d=0.0).nondim().mass_ratio == 0.0  # m_d unused by the rigid rotor
    assert SystemSpec(G=0.0).nondim().eps == 0.0  # balanced
    assert SystemSpec(e_u=5e-6, G=1000.0).nondim().eps == pytest.approx(5e-6 / 38.1e-6)  # e_u overrides G
    # eta = 0 is rejected as well (Eq. 10 would no longer be an ODE); document it here
    with pytest.raises(ParameterError, match="eta"):
        SystemSpec(eta=0.0)


def test_unknown_field_and_system():
    with pytest.raises(ParameterError, match="alpha"):
        reference_system(alpha=0.1)
    with pytest.raises(ParameterError, match="nonexistent"):
        variation("nonexistent")
    with pytest.raises(ParameterError, match="nonexistent"):
        system_from_name_or_file("nonexistent")
    with pytest.raises(ParameterError, match="load_per_bearing"):
        validation_case(0.0)


def test_load_config(tmp_path):
    good = tmp_path / "good.toml"
    good.write_text('base = "af1"\neta = 0.5\nrotor = "jeffcott"\n')
    spec = load_config(good)
    assert spec.alpha_f == 1.0 and spec.eta == 0.5 and spec.k_s_bar == 1.0
    assert system_from_name_or_file(str(good)) == spec
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("alpha_f = 0.2\nfoil_thickness = 1e-4\n")
    with pytest.raises(ParameterError, match="foil_thickness"):
        load_config(unknown)
    bad = tmp_path / "bad.toml"
    bad.write_text("alpha_f = -0.2\n")
    with pytest.raises(ParameterError, match="alpha_f"):
        load_config(bad)
    with pytest.raises(ParameterError, match="does not exist"):
        load_config(tmp_path / "missing.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("alpha_f = = 1\n")
    with pytest.raises(ParameterError, match="TOML"):
        load_config(broken)
    base_bad = tmp_path / "base.toml"
    base_bad.write_text('base = "nope"\n')
    with pytest.raises(ParameterError, match="nope"):
        load_config(base_bad)


def test_bump_foil_compliance_hand_computation():
    # l0 = 1.778 mm, t_b = 0.1016 mm, s0 = 4.572 mm, E = 207 GPa, nu = 0.29, p0 = 1e5 Pa, c = 38.1 um:
    # (l0/t_b)^3 = 17.5^3 = 5359.375; 1 - nu^2 = 0.9159;
    # 2 p0 (l0/t_b)^3 (1 - nu^2) s0 = 2e5 * 5359.375 * 0.9159 * 4.572e-3 = 4.488471e6 [Pa m];
    # c E = 38.1e-6 * 2.07e11 = 7.8867e6 [Pa m]  ->  alpha_f = 0.569119
    a = bump_foil_compliance(1.778e-3, 0.1016e-3, 4.572e-3, 2.07e11, 0.29, 1e5, 38.1e-6)
    assert a == pytest.approx(0.569119, rel=1e-6)
    for kwargs, field in ((dict(E=0.0), "E"), (dict(nu=0.5), "nu"), (dict(t_b=-1.0), "t_b"), (dict(c=NAN), "c")):
        args = dict(l0=1.778e-3, t_b=0.1016e-3, s0=4.572e-3, E=2.07e11, nu=0.29, p0=1e5, c=38.1e-6)
        args.update(kwargs)
        with pytest.raises(ParameterError, match=rf"\b{field}\b"):
            bump_foil_compliance(**args)


def test_unbalance_eccentricity():
    assert unbalance_eccentricity(2.5) == pytest.approx(1.0e-6, rel=1e-12)
    assert unbalance_eccentricity(6.3) == pytest.approx(2.52e-6, rel=1e-12)
    # the paper's worked example: G2.5 at 2500 rpm = 261.8 rad/s gives 9.55 um
    assert unbalance_eccentricity(2.5, 2500 * 2 * math.pi / 60) == pytest.approx(9.549e-6, rel=1e-3)
    with pytest.raises(ParameterError, match="G"):
        unbalance_eccentricity(-1.0)
    with pytest.raises(ParameterError, match="omega_r"):
        unbalance_eccentricity(2.5, 0.0)


def test_reference_dimensionless_groups_by_hand():
    """From docs/model.md's SI values: R = 19.05 mm, L = 38.1 mm, c = R/500, mu = 1.8e-5 Pa s, p0 = 1e5 Pa,
    g = 9.81 m/s^2, m_j = 0.5 kg, m_d = 1 kg, G6.3.

    t*    = 6 mu R^2/(p0 c^2) = 6 * 1.8e-5 * 500^2 / 1e5                 = 2.7e-4 s
    zeta  = p0 R L t*^2/(m_j c) = 1e5 * 19.05e-3 * (38.1e-3/38.1e-6) * 7.29e-8 / 0.5
          = 1e5 * 19.05e-3 * 1000 * 1.458e-7                               = 0.277749
    sigma = g t*^2 / c = 9.81 * 7.29e-8 / 38.1e-6                            = 0.01877031...
    eps   = (6.3e-3 / 2500) / 38.1e-6 = 2.52e-6 / 38.1e-6                    = 0.0661417...
    """
    spec = reference_system()
    assert spec.t_star == pytest.approx(2.7e-4, rel=1e-12)
    p = spec.nondim()
    assert p.zeta == pytest.approx(0.277749, rel=1e-9)
    assert p.sigma == pytest.approx(9.81 * 7.29e-8 / 38.1e-6, rel=1e-12)
    assert p.sigma == pytest.approx(0.0187703, rel=1e-6)
    assert p.eps == pytest.approx(2.52 / 38.1, rel=1e-12)
    assert p.kappa == 0.5 and p.mass_ratio == 1.0 and p.k_s == 1.0
    assert p.alpha_f == 0.1 and p.eta == 0.05 and p.w_ext == 0.0
    # docs/model.md's closed forms in the physical constants (zeta = 36 mu^2 L R^5/(m_j p0 c^5), sigma with R^4)
    mu, R, L, c, p0 = 1.8e-5, 19.05e-3, 38.1e-3, 38.1e-6, 1e5
    assert p.zeta == pytest.approx(36 * mu**2 * L * R**5 / (0.5 * p0 * c**5), rel=1e-12)
    assert p.sigma == pytest.approx(36 * mu**2 * R**4 * 9.81 / (p0**2 * c**5), rel=1e-12)
    # speed: Omega_bar = Omega t*  (1000 rpm = 104.72 rad/s -> 0.028274)
    assert spec.omega_bar(1000.0) == pytest.approx(1000 * 2 * math.pi / 60 * 2.7e-4, rel=1e-12)
    assert spec.rpm(spec.omega_bar(1234.0)) == pytest.approx(1234.0)
    # extra load: 10 N over p0 R L = 72.58 N
    assert reference_system(load=10.0).nondim().w_ext == pytest.approx(10.0 / (1e5 * 19.05e-3 * 38.1e-3))


@pytest.mark.parametrize("convert, name", [("omega_bar", "rpm"), ("rpm", "omega_bar")])
def test_speed_conversions_refuse_negative_speeds(convert, name):
    """A new user's audit: spec.omega_bar(-100.0) returned -0.0028 (NaN was refused, a negative speed was not)."""
    spec = reference_system()
    with pytest.raises(ParameterError, match=f"{name} must be >= 0"):
        getattr(spec, convert)(-100.0)
    assert getattr(spec, convert)(0.0) == 0.0


def test_validation_case_groups():
    spec = validation_case(15.0)
    p = spec.nondim()
    assert spec.rotor == "rigid" and p.rotor == "rigid"
    # alpha_f = p0 / (k_f c) = 1.01325e5 / (4.6417e9 * 31.8e-6)
    assert p.alpha_f == pytest.approx(0.686456, rel=1e-5)
    assert spec.m_j == pytest.approx(15.0 / 9.81)
    assert p.eta == 0.25 and p.eps == 0.0 and p.mass_ratio == 0.0
    assert spec.bearing_weight == pytest.approx(15.0)


def test_named_variations():
    assert variation("ks0.3").nondim().k_s == 0.3
    assert variation("af0.01").alpha_f == 0.01
    assert variation("eta0.5").eta == 0.5
    assert variation("G0").nondim().eps == 0.0
    assert set(gfbjax.VARIATIONS) >= {"reference", "ks0.3", "ks3", "af0.01", "af1", "eta0.005", "eta0.5", "G0",
                                      "G1", "G2.5", "G6.3"}


@pytest.mark.parametrize("geom, word", [((1.5e-3, 1e-2, 4.5e-3), "t_b"), ((1.5e-3, 1e-4, 1e-3), "s0")])
def test_bump_compliance_refuses_what_is_no_bump_foil(geom, word):
    """A foil thicker than its bump, or overlapping bumps: the thin-beam formula does not apply (a fresh user's
    report: the inverse refused these, the forward formula gave a number)."""
    l0, t_b, s0 = geom
    with pytest.raises(ParameterError, match=word):
        bump_foil_compliance(l0, t_b, s0, 2.07e11, 0.29, 1e5, 38.1e-6)
