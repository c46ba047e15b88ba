"""Self-describing branch files: npz + JSON round trip with meta, units and component names; what the JSON records
of a GFB system; one-line BranchFileError for missing, corrupt, truncated, foreign or inconsistent files; xarray and
netCDF export; ``gfbjax runup --cycles`` refusing a branch of another system before integrating."""

from __future__ import annotations

import json
import math

import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax import SystemSpec, reference_system
from gfbjax.cli import main
from gfbjax.cont import (Branch, BranchFileError, EquilibriumProblem, EquilibriumSettings, Outcome, PointRecord,
                         SpecialPoint, continue_equilibria)

TINY_GRID = ["--nx", "16", "--nz", "2"]


def _branch(P: int = 5, k: int = 2, n: int = 3, *, special: bool = True, states: bool = True) -> Branch:
    """A hand-made cycle branch: P points, k recorded components, n multipliers, two special points."""
    rng = np.random.default_rng(0)
    pts = []
    for i in range(P):
        mu = rng.normal(size=n) + 1j * rng.normal(size=n)
        pts.append(PointRecord(lam=0.1 + 0.05 * i, period=2 * np.pi / (0.1 + 0.05 * i), l2=1.0 + i, xmax=rng.random(k),
                               xmin=-rng.random(k), multipliers=mu, stable=bool(i % 2), trivial_error=1e-12 * i,
                               newton_iterations=2 + i, ds=0.01 * (i + 1), tangent_lam=0.9,
                               state={"xm": rng.random((4, k))} if states else None))
    sp, sp_states = [], []
    if special:
        sp = [SpecialPoint("NS", lam=0.17, index=2, spectrum=np.array([1j, -1j, 0.5]), located=True, residual=1e-10,
                           period=37.0, angle=1.25, state=0, lam_error=3e-5),
              SpecialPoint("LPC", lam=0.26, index=P, spectrum=np.array([1.0, 0.2, 0.1 + 0.1j]), located=False)]
        sp_states = [{"xm": np.ones((4, k))}]
    b = Branch.from_points("cycles", list(range(10, 10 + k)), pts, sp, sp_states, Outcome.REACHED_END,
                           "reached lam_max", m=4, shared_state={"mesh": np.linspace(0, 1, 4)} if states else None)
    b.component_names = [f"c{i}" for i in range(k)]
    b.units = {"lam": "Omega_bar (dimensionless speed)", "period": "tau = t / t*", "xmax": "over clearance c"}
    b.meta = {"system": {"name": "tiny", "values": [1.0, 2.5], "flag": True}, "note": "hand made", "count": 3,
              "ratio": 0.5, "none": None, "np": np.float64(2.0), "arr": np.arange(3)}
    return b


def _assert_single_line(exc: BaseException, *fragments: str) -> None:
    text = str(exc)
    assert "\n" not in text and text.strip() == text and text, text
    for f in fragments:
        assert f in text, (f, text)


# ------------------------------------------------------------------------------------------------- round trip
def test_round_trip_keeps_meta_outcome_message_special(tmp_path):
    b = _branch()
    npz, js = b.save(tmp_path / "br")
    assert npz.name == "br.npz" and js.name == "br.json"
    back = Branch.load(tmp_path / "br.npz")  # either file, or neither suffix
    for key in ("lam", "period", "l2", "xmax", "xmin", "multipliers", "stable", "trivial_error",
                "newton_iterations", "ds", "tangent_lam"):
        np.testing.assert_array_equal(getattr(back, key), getattr(b, key), err_msg=key)
    assert back.kind == "cycles" and back.components == b.components and back.m == 4
    assert back.outcome is Outcome.REACHED_END and back.message == "reached lam_max"
    assert back.component_names == ["c0", "c1"] and back.units == b.units
    assert back.meta == json.loads(json.dumps(b.meta, default=lambda o: o.tolist()))
    assert back.meta["system"] == {"name": "tiny", "values": [1.0, 2.5], "flag": True} and back.meta["arr"] == [0, 1, 2]
    assert len(back.special) == 2
    ns, lpc = back.special
    assert (ns.type, ns.index, ns.located, ns.angle, ns.state, ns.period) == ("NS", 2, True, 1.25, 0, 37.0)
    np.testing.assert_array_equal(ns.spectrum, b.special[0].spectrum)
    assert lpc.type == "LPC" and not lpc.located and math.isnan(lpc.residual) and lpc.index == len(b)
    assert ns.lam_error == 3e-5 and math.isnan(lpc.lam_error)
    np.testing.assert_array_equal(back.special_states[0]["xm"], b.special_states[0]["xm"])
    np.testing.assert_array_equal(back.states["xm"], b.states["xm"])
    np.testing.assert_array_equal(back.states["mesh"], b.states["mesh"])


def test_round_trip_of_an_engine_branch(tmp_path):
    """A real branch of the engine (2-state Hopf normal form) with its Hopf point survives save/load."""
    def f(x, lam, w):
        r2 = x[0] ** 2 + x[1] ** 2
        return jnp.stack([lam * x[0] - w * x[1] - r2 * x[0], w * x[0] + lam * x[1] - r2 * x[1]])

    br = continue_equilibria(EquilibriumProblem(f, 2, jnp.asarray(2.0)), EquilibriumSettings(ds=0.07, max_points=8),
                             np.zeros(2), -0.3)
    assert br.special_of("HOPF")
    br.meta = {"system": "Hopf normal form", "w": 2.0}
    br.save(tmp_path / "eq")
    back = Branch.load(tmp_path / "eq")
    assert back.meta == br.meta and back.outcome is br.outcome and back.message == br.message
    h0, h1 = br.special_of("HOPF")[0], back.special_of("HOPF")[0]
    assert h1.lam == h0.lam and h1.omega == h0.omega and h1.located == h0.located
    np.testing.assert_array_equal(back.multipliers, br.multipliers)


def test_files_are_plain_numpy_and_json_with_format_key(tmp_path):
    b = _branch()
    npz, js = b.save(tmp_path / "br")
    head = json.loads(js.read_text())
    assert head["format"] == "gfbjax.cont.Branch" and head["version"] == 2
    assert head["points"] == len(b) and head["component_names"] == ["c0", "c1"]
    assert head["units"]["lam"].startswith("Omega_bar") and head["meta"]["note"] == "hand made"
    with np.load(npz) as z:
        assert set(head["keys"]) == set(z.files)
        np.testing.assert_array_equal(z["multipliers"], b.multipliers)


def test_meta_not_jsonable_is_refused_before_writing(tmp_path):
    b = _branch()
    b.meta = {"bad": object()}
    with pytest.raises(ValueError, match="meta"):
        b.save(tmp_path / "br")
    assert not list(tmp_path.iterdir())


def test_gfb_branch_json_records_spec_grid_names_units_rpm(tmp_path):
    """What analyses.cycles attaches (no continuation needed: the description is built from params and spec)."""
    from gfbjax.analyses.cycles import branch_meta, describe_branch
    from gfbjax.cli.commands._common import traced_params

    spec = reference_system(Nx=16, Nz=2)
    b = describe_branch(_branch(k=4), branch_meta(traced_params(spec), "unbalance_response", spec))
    _, js = b.save(tmp_path / "gfb")
    head = json.loads(js.read_text())  # plain json
    meta = head["meta"]
    assert meta["spec"] == json.loads(json.dumps(spec.to_dict()))
    assert meta["rpm_per_omega_bar"] == pytest.approx(spec.rpm(1.0)) and meta["t_star_s"] == pytest.approx(spec.t_star)
    assert meta["grid"]["Nx"] == 16 and meta["grid"]["Nz"] == 2 and meta["grid"]["n_theta"] == 15
    assert meta["params"]["alpha_f"] == pytest.approx(0.1) and meta["params"]["rotor"] == "jeffcott"
    lay = meta["state_layout"]
    assert lay["oscillator"] is True and lay["slices"]["rotor"][1] - lay["slices"]["rotor"][0] == 8
    assert {"time", "speed", "lengths", "axes", "theta0"} <= set(meta["conventions"])
    assert head["component_names"] == ["x_j", "y_j", "x_d", "y_d"]
    assert "Omega_bar" in head["units"]["lam"] and "clearance" in head["units"]["xmax"]
    assert head["units"]["period"].startswith("tau")


def test_gfb_meta_refuses_a_spec_of_another_system():
    from gfbjax import ParameterError
    from gfbjax.analyses.cycles import branch_meta
    from gfbjax.cli.commands._common import traced_params

    spec = reference_system(Nx=16, Nz=2)
    with pytest.raises(ParameterError, match="alpha_f"):
        branch_meta(traced_params(spec.replace(alpha_f=1.0)), "equilibria", spec)


# ------------------------------------------------------------------------------------------------- bad files
def _corrupt_npz(base):
    base.with_suffix(".npz").write_bytes(b"PK\x03\x04 this is not really a zip archive" * 10)


def _truncate_npz(base):
    p = base.with_suffix(".npz")
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def _text_npz(base):
    base.with_suffix(".npz").write_text("lam,period\n0.1,2\n")


def _npy_npz(base):
    with open(base.with_suffix(".npz"), "wb") as fh:
        np.save(fh, np.arange(3))


def _json(edit):
    def apply(base):
        p = base.with_suffix(".json")
        head = json.loads(p.read_text())
        p.write_text(json.dumps(edit(head)))
    return apply


def _foreign_json(base):
    base.with_suffix(".json").write_text(json.dumps({"name": "something else", "values": [1, 2, 3]}))


def _json_list(base):
    base.with_suffix(".json").write_text("[1, 2, 3]")


def _json_garbage(base):
    base.with_suffix(".json").write_text('{"format": "gfbjax.cont.Branch", "kind": ')


def _summary_json(base):  # the cycles.json a CLI command writes next to the branch
    base.with_suffix(".json").write_text(json.dumps({"command": "cycles", "counts": {"points": 5}}))


def _short_lam(base):
    p = base.with_suffix(".npz")
    with np.load(p) as z:
        data = {k: z[k] for k in z.files}
    data["lam"] = data["lam"][:-1]
    np.savez(p, **data)


def _narrow_xmax(base):
    p = base.with_suffix(".npz")
    with np.load(p) as z:
        data = {k: z[k] for k in z.files}
    data["xmax"] = data["xmax"][:, :1]
    np.savez(p, **data)


def _other_save(base):  # an npz of another (shorter) branch next to this JSON
    _branch(P=3).save(base.with_name("other"))
    base.with_suffix(".npz").write_bytes(base.with_name("other.npz").read_bytes())


def _drop_array(base):
    p = base.with_suffix(".npz")
    with np.load(p) as z:
        data = {k: z[k] for k in z.files if k != "stable"}
    np.savez(p, **data)


def _pop(key):
    return _json(lambda h: {k: v for k, v in h.items() if k != key})


def _set(key, value):
    return _json(lambda h: {**h, key: value})


@pytest.mark.parametrize("damage, fragments", [
    (lambda base: base.with_suffix(".npz").unlink(), ["br.npz", "no such file"]),
    (lambda base: base.with_suffix(".json").unlink(), ["br.json", "no such file"]),
    (_corrupt_npz, ["br.npz", "corrupt"]),
    (_truncate_npz, ["br.npz", "corrupt"]),
    (_text_npz, ["br.npz"]),
    (_npy_npz, ["br.npz", "not an npz"]),
    (_foreign_json, ["br.json", "not a branch file"]),
    (_json_list, ["br.json", "not a branch file"]),
    (_json_garbage, ["br.json", "not valid JSON"]),
    (_summary_json, ["br.json", "gfbjax cycles"]),
    (_set("format", "gfbjax.transient"), ["br.json", "gfbjax.transient"]),
    (_set("version", 99), ["br.json", "newer"]),
    (_set("kind", "tori"), ["br.json", "kind"]),
    (_set("components", "x_j"), ["br.json", "components"]),
    (_set("outcome", "exploded"), ["br.json", "outcome"]),
    (_set("special", [{"type": "NS"}]), ["br.json", "special[0]"]),
    (_set("special", [{"type": "XX", "lam": 1.0, "index": 0, "located": True}]), ["br.json", "special[0]"]),
    (_set("meta", [1, 2]), ["br.json", "meta"]),
    (_set("component_names", ["only one"]), ["br.json", "component_names"]),
    (_set("m", "four"), ["br.json", "'m'"]),
    (_pop("kind"), ["br.json", "kind"]),
    (_short_lam, ["br.npz", "different lengths"]),
    (_narrow_xmax, ["br.npz", "columns"]),
    (_other_save, ["br.npz", "different saves"]),
    (_drop_array, ["br.npz", "stable"]),
])
def test_bad_files_give_one_line_branch_file_error(tmp_path, damage, fragments):
    base = tmp_path / "br"
    _branch().save(base)
    damage(base)
    with pytest.raises(BranchFileError) as info:
        Branch.load(base)
    assert isinstance(info.value, ValueError)  # callers that catch ValueError keep working
    _assert_single_line(info.value, *fragments)


def test_a_folder_is_not_a_branch_file(tmp_path):
    with pytest.raises(BranchFileError) as info:
        Branch.load(tmp_path)
    _assert_single_line(info.value, "folder", "branch.npz")


def test_every_truncation_gives_branch_file_error(tmp_path):
    base = tmp_path / "br"
    npz, _ = _branch().save(base)
    raw = npz.read_bytes()
    for n in range(0, len(raw), max(1, len(raw) // 60)):
        npz.write_bytes(raw[:n])
        with pytest.raises(BranchFileError) as info:
            Branch.load(base)
        _assert_single_line(info.value, "br.npz")


def test_older_files_without_format_still_load(tmp_path):
    """Version 1 (outcome, no format/meta) and version 0 (free-text reason, special points with 'multipliers')."""
    base = tmp_path / "br"
    b = _branch()
    b.save(base)
    js = base.with_suffix(".json")
    head = json.loads(js.read_text())
    v1 = {k: v for k, v in head.items() if k not in ("format", "version", "points", "component_names", "units",
                                                     "meta")}
    js.write_text(json.dumps(v1))
    old = Branch.load(base)
    assert old.meta == {} and old.component_names is None and old.outcome is Outcome.REACHED_END
    np.testing.assert_array_equal(old.lam, b.lam)

    v0 = {k: v for k, v in v1.items() if k not in ("outcome", "message")}
    v0["reason"] = "max_points reached"
    v0["special"] = [{"type": "HOPF", "index": 1, "lam": 0.15, "period": 3.0, "multipliers": [[0.0, 2.0]],
                      "located": True, "angle": 2.0, "state": None}]
    js.write_text(json.dumps(v0))
    older = Branch.load(base)
    assert older.outcome is Outcome.MAX_POINTS and older.message == "max_points reached"
    (h,) = older.special
    assert h.type == "HOPF" and h.omega == 2.0 and h.angle is None and h.spectrum[0] == 2j


# ------------------------------------------------------------------------------------------------- xarray
def test_to_xarray_dims_coords_attrs():
    b = _branch()
    ds = b.to_xarray()
    assert dict(ds.sizes) == {"point": 5, "component": 2, "multiplier": 3, "special": 2}
    np.testing.assert_array_equal(ds["lam"].values, b.lam)
    assert ds["lam"].dims == ("point",) and "lam" in ds.coords
    assert list(ds["component"].values) == ["c0", "c1"] and list(ds["state_index"].values) == [10, 11]
    np.testing.assert_array_equal(ds["xmax"].values, b.xmax)
    np.testing.assert_array_equal(ds["multipliers_real"].values + 1j * ds["multipliers_imag"].values, b.multipliers)
    assert ds["stable"].dtype == bool and ds["period"].attrs["units"] == "tau = t / t*"
    assert ds["lam"].attrs["units"].startswith("Omega_bar") and ds["xmax"].attrs["units"] == "over clearance c"
    assert list(ds["special_type"].values) == ["NS", "LPC"]
    assert ds["special_angle"].values[0] == 1.25 and math.isnan(ds["special_angle"].values[1])
    assert ds["special_lam_error"].values[0] == 3e-5 and math.isnan(ds["special_lam_error"].values[1])
    assert ds.attrs["format"] == "gfbjax.cont.Branch" and ds.attrs["outcome"] == "reached_end"
    assert ds.attrs["message"] == "reached lam_max" and ds.attrs["m"] == 4
    assert json.loads(ds.attrs["meta_system"]) == {"name": "tiny", "values": [1.0, 2.5], "flag": True}
    assert ds.attrs["meta_note"] == "hand made" and ds.attrs["meta_count"] == 3
    assert json.loads(ds.attrs["meta_none"]) is None and json.loads(ds.attrs["units"]) == b.units


def test_to_netcdf_reads_back_equal(tmp_path):
    import xarray as xr

    b = _branch()
    path = b.to_netcdf(tmp_path / "br.nc")
    with xr.open_dataset(path) as ds:
        ds.load()
    ref = b.to_xarray()
    for name in ("period", "l2", "xmax", "xmin", "multipliers_real", "multipliers_imag", "stable", "trivial_error",
                 "newton_iterations", "ds", "tangent_lam", "special_lam", "special_index", "special_located"):
        np.testing.assert_array_equal(ds[name].values, ref[name].values, err_msg=name)
    np.testing.assert_array_equal(ds["lam"].values, b.lam)
    assert ds["stable"].dtype == bool
    assert [str(v) for v in ds["special_type"].values] == ["NS", "LPC"]
    assert [str(v) for v in ds["component"].values] == ["c0", "c1"]
    assert json.loads(ds.attrs["meta_system"]) == {"name": "tiny", "values": [1.0, 2.5], "flag": True}
    assert ds.attrs["outcome"] == "reached_end" and ds["xmax"].attrs["units"] == "over clearance c"


def test_to_netcdf_without_special_points_or_names(tmp_path):
    import xarray as xr

    b = _branch(special=False, states=False)
    b.component_names, b.meta = None, {}
    with xr.open_dataset(b.to_netcdf(tmp_path / "plain.nc")) as ds:
        assert "special" not in ds.sizes and ds.sizes["point"] == 5
        assert [str(v) for v in ds["component"].values] == ["10", "11"]


# ------------------------------------------------------------------------------------------------- runup --cycles
def _gfb_branch(tmp_path, spec: SystemSpec, name: str = "branch"):
    """A branch file described as computed for ``spec`` (the arrays are made up: only the description matters)."""
    from gfbjax.analyses.cycles import branch_meta, describe_branch
    from gfbjax.cli.commands._common import traced_params

    b = describe_branch(_branch(k=4), branch_meta(traced_params(spec), "unbalance_response", spec))
    b.save(tmp_path / name)
    return tmp_path / f"{name}.npz"


def _run(argv, capsys):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_runup_refuses_branch_of_another_system_before_integrating(tmp_path, capsys):
    path = _gfb_branch(tmp_path, reference_system(Nx=16, Nz=2))
    code, out, err = _run(["runup", "--system", "ks3", *TINY_GRID, "--cycles", str(path), "--out",
                           str(tmp_path / "out")], capsys)
    assert code == 2, err
    assert "--cycles" in err and "k_s_bar" in err and "1.0" in err and "3.0" in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "out" / "runup.npz").exists()


@pytest.mark.parametrize("damage", [_corrupt_npz, _foreign_json, _short_lam])
def test_runup_bad_branch_file_exits_2(tmp_path, capsys, damage):
    path = _gfb_branch(tmp_path, reference_system(Nx=16, Nz=2))
    damage(path.with_suffix(""))
    code, _, err = _run(["runup", *TINY_GRID, "--cycles", str(path), "--out", str(tmp_path / "out")], capsys)
    assert code == 2 and "--cycles" in err and ("branch.npz" in err or "branch.json" in err)
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_cycle_overlay_accepts_same_system_on_another_grid(tmp_path):
    from gfbjax.cli.commands.runup import _cycle_overlay

    path = _gfb_branch(tmp_path, reference_system(Nx=24, Nz=3))
    ov = _cycle_overlay(str(path), reference_system(Nx=16, Nz=2), "reference")
    assert ov["x_max"].shape == (5,)
    # the same unbalance stated as e_u instead of G / omega_r is the same system
    spec = reference_system()
    ov = _cycle_overlay(str(path), spec.replace(e_u=spec.eccentricity_u), "reference")
    assert ov is not None


def test_cycle_overlay_refuses_other_unbalance_and_equilibria(tmp_path):
    from gfbjax import ParameterError
    from gfbjax.cli.commands.runup import _cycle_overlay

    path = _gfb_branch(tmp_path, reference_system(Nx=16, Nz=2))
    with pytest.raises(ParameterError, match="unbalance e_u"):
        _cycle_overlay(str(path), reference_system(G=2.5), "G2.5")
    b = Branch.load(path)
    b.kind = "equilibria"
    b.save(tmp_path / "eq")
    with pytest.raises(ParameterError, match="kind"):
        _cycle_overlay(str(tmp_path / "eq"), reference_system(), "reference")


def test_cycle_overlay_checks_groups_when_no_spec_was_recorded(tmp_path):
    from gfbjax import ParameterError
    from gfbjax.analyses.cycles import branch_meta, describe_branch
    from gfbjax.cli.commands._common import traced_params
    from gfbjax.cli.commands.runup import _cycle_overlay

    spec = reference_system(Nx=16, Nz=2)
    describe_branch(_branch(k=4), branch_meta(traced_params(spec), "unbalance_response")).save(tmp_path / "b")
    assert _cycle_overlay(str(tmp_path / "b"), reference_system(), "reference") is not None
    with pytest.raises(ParameterError, match="Params.alpha_f"):
        _cycle_overlay(str(tmp_path / "b"), reference_system(alpha_f=1.0), "af1")


def test_cycle_overlay_warns_for_a_branch_without_system(tmp_path, capsys):
    from gfbjax.cli.commands.runup import _cycle_overlay

    b = _branch(k=4)
    b.meta, b.component_names = {}, None
    b.save(tmp_path / "old")
    ov = _cycle_overlay(str(tmp_path / "old"), reference_system(), "reference")
    np.testing.assert_array_equal(ov["speed"], b.lam)
    err = capsys.readouterr().err
    assert "warning" in err and "records no system" in err and len(err.strip().splitlines()) == 1


def test_empty_branch_saves_loads_and_exports(tmp_path):
    """A branch whose start failed has no points: still a valid file of each kind."""
    import xarray as xr

    b = Branch.from_points("cycles", [0, 1], [], [], [], Outcome.START_FAILED, "no start")
    b.save(tmp_path / "empty")
    back = Branch.load(tmp_path / "empty")
    assert len(back) == 0 and back.outcome is Outcome.START_FAILED and back.xmax.shape == (0, 2)
    with xr.open_dataset(b.to_netcdf(tmp_path / "empty.nc")) as ds:
        assert ds.sizes["point"] == 0 and ds.attrs["outcome"] == "start_failed"
