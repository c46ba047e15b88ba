"""gfbjax.sweep and ``gfbjax sweep``: figures equal to the analyses called directly on each design, the Dataset
layout and its netCDF file, resume and the refusal of a folder of another sweep, checks before any computation,
failures recorded per design, dask.distributed (a LocalCluster of 2 processes, shared by the tests) equal to serial,
a worker killed during a sweep, the command line and the plots.

Tiny problems throughout: grid Nx=16, Nz=2; equilibria over Omega_bar 0.2 -> 0.6 (the Hopf point of these designs
lies near 0.39-0.40) with small steps, so that one design takes about a second and a worker can be killed while it
computes one; cycles on N=8 intervals of m=3 points.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import signal

import numpy as np
import pytest

import gfbjax
from gfbjax.params import ParameterError
from gfbjax.sweep import Cycles, Energy, Equilibria, Optimum, Static, run_sweep

BASE = gfbjax.reference_system(Nx=16, Nz=2)
GRID = {"alpha_f": [0.5, 1.0], "eta": [0.05, 0.2]}
# small fixed steps: ~350 points, about a second per design, so that a killed worker is caught mid-design
EQ = Equilibria(0.2, 0.6, ds=0.002, ds_max=0.002, max_points=1000)
EQ_FAST = Equilibria(0.2, 0.6)  # default steps: ~25 points, a tenth of a second per design


@pytest.fixture(scope="module")
def serial():
    """The reference: the grid run serially in this process, nothing stored."""
    return run_sweep(BASE, GRID, analyses=[EQ], progress=False, compilation_cache=False)


@pytest.fixture(scope="module")
def cluster():
    import distributed

    from gfbjax.sweep import local_cluster

    with local_cluster(2) as lc:
        with distributed.Client(lc) as client:
            yield lc, client


# -- figures and layout --------------------------------------------------------------------------------------------

def test_grid_figures_equal_direct_analyses(serial):
    from gfbjax.analyses.cycles import continue_gfb_equilibria

    assert serial.hopf_omega_bar.dims == ("alpha_f", "eta")
    for a in (0.5, 1.0):
        eta = 0.2
        spec = BASE.replace(alpha_f=a, eta=eta)
        br = continue_gfb_equilibria(spec.nondim().traced(), 0.2, 0.6, EQ.cont_settings(), spec=spec)
        hopf = sorted((s for s in br.special if s.type == "HOPF"), key=lambda s: s.index)
        assert hopf and all(h.lam > hopf[0].lam for h in hopf[1:])  # the first along the branch is the lowest
        row = serial.sel(alpha_f=a, eta=eta)
        assert float(row.hopf_count) == len(hopf)
        assert float(row.hopf_omega_bar) == pytest.approx(hopf[0].lam, rel=1e-12, abs=0)
        assert float(row.hopf_whirl_omega) == pytest.approx(abs(hopf[0].omega), rel=1e-12)
        assert float(row.hopf_rpm) == pytest.approx(spec.rpm(hopf[0].lam), rel=1e-12)
        assert float(row.hopf_frequency_hz) == pytest.approx(abs(hopf[0].omega) / spec.t_star / (2 * math.pi),
                                                            rel=1e-12)
        assert float(row.equilibria_points) == len(br)
        assert str(row.equilibria_outcome.values) == str(br.outcome) == "reached_end"
        assert str(row.outcome.values) == "ok" and str(row.message.values) == ""
    # whirl below the running speed, as in the paper's self-excited whirl
    assert np.all((serial.hopf_whirl_ratio > 0.2) & (serial.hopf_whirl_ratio < 0.6))


def test_static_figures_equal_solve_equilibrium(tmp_path):
    from gfbjax.analyses.static import solve_equilibrium

    speeds = (0.2, 0.5)
    ds = run_sweep(BASE, {"k_s_bar": [0.5, 2.0]}, analyses=[Static(speeds)], progress=False,
                   compilation_cache=False)
    assert ds.static_eccentricity.dims == ("k_s_bar", "static_omega_bar")
    np.testing.assert_array_equal(ds.static_omega_bar, speeds)
    for k in (0.5, 2.0):
        spec = BASE.replace(k_s_bar=k)
        for w in speeds:
            r = solve_equilibrium(spec.nondim(), w)
            row = ds.sel(k_s_bar=k, static_omega_bar=w)
            assert float(row.static_eccentricity) == pytest.approx(r.eccentricity, rel=1e-9)
            assert float(row.static_h_min_um) == pytest.approx(r.h_min * spec.c * 1e6, rel=1e-9)
            assert float(row.static_attitude_deg) == pytest.approx(r.attitude_deg, rel=1e-9, abs=1e-9)
            assert str(row.static_outcome.values) == "converged"


def test_dataset_attrs_units_and_netcdf(tmp_path):
    import xarray as xr

    ds = run_sweep(BASE, GRID, analyses=[EQ_FAST], out=tmp_path, progress=False, compilation_cache=False)
    assert json.loads(ds.attrs["base_spec"]) == BASE.to_dict()
    assert json.loads(ds.attrs["analyses_settings"])[0] == {"analysis": "equilibria", **dataclasses.asdict(EQ_FAST)}
    assert ds.attrs["gfbjax_version"] == gfbjax.__version__
    assert ds.hopf_omega_bar.attrs["units"] == "Omega_bar = Omega t*" and ds.hopf_rpm.attrs["units"] == "rpm"
    assert ds.hopf_frequency_hz.attrs["units"] == "Hz"
    np.testing.assert_array_equal(ds.alpha_f, GRID["alpha_f"])
    np.testing.assert_array_equal(ds.eta, GRID["eta"])
    assert np.all((ds.hopf_omega_bar > 0.35) & (ds.hopf_omega_bar < 0.45))
    with xr.open_dataset(tmp_path / "sweep.nc") as back:
        np.testing.assert_array_equal(back.hopf_omega_bar, ds.hopf_omega_bar)
        assert back.hopf_omega_bar.attrs["units"] == "Omega_bar = Omega t*"
        assert list(back.outcome.values.ravel()) == ["ok"] * 4
        assert back.attrs["base_spec"] == ds.attrs["base_spec"]
    assert len(list((tmp_path / "designs").glob("*.json"))) == 4
    assert not list(tmp_path.rglob("*.tmp"))


# -- storage and resume ----------------------------------------------------------------------------------------------

def test_resume_computes_only_new_designs(tmp_path, monkeypatch):
    calls = []
    original = Equilibria.run

    def counting(self, spec):
        calls.append((spec.alpha_f, spec.eta))
        return original(self, spec)

    monkeypatch.setattr(Equilibria, "run", counting)
    first = run_sweep(BASE, {"alpha_f": [0.5, 1.0], "eta": [0.05]}, analyses=[EQ_FAST], out=tmp_path, progress=False,
                      compilation_cache=False)
    assert sorted(calls) == [(0.5, 0.05), (1.0, 0.05)]
    files = sorted((tmp_path / "designs").glob("*.json"))
    stamps = {f.name: f.stat().st_mtime_ns for f in files}
    calls.clear()
    # the same grid extended by one value: only the new design is computed, the stored ones are read back
    second = run_sweep(BASE, {"alpha_f": [0.5, 1.0, 2.0], "eta": [0.05]}, analyses=[EQ_FAST], out=tmp_path,
                       progress=False, compilation_cache=False)
    assert calls == [(2.0, 0.05)]
    assert (second.attrs["n_reused"], second.attrs["n_computed"]) == (2, 1)
    assert {f.name: f.stat().st_mtime_ns for f in files} == stamps
    np.testing.assert_array_equal(second.hopf_omega_bar.sel(alpha_f=[0.5, 1.0]), first.hopf_omega_bar)
    calls.clear()
    run_sweep(BASE, {"alpha_f": [0.5, 1.0, 2.0], "eta": [0.05]}, analyses=[EQ_FAST], out=tmp_path, progress=False,
              compilation_cache=False)
    assert calls == []


def test_folder_of_another_sweep_is_refused(tmp_path):
    run_sweep(BASE, {"alpha_f": [0.5]}, analyses=[EQ_FAST], out=tmp_path, progress=False, compilation_cache=False)
    before = sorted(p.name for p in (tmp_path / "designs").iterdir())
    other = Equilibria(0.2, 0.6, max_points=199)
    with pytest.raises(ParameterError, match=r"another system or other analysis settings.*max_points: 200 there"):
        run_sweep(BASE, {"alpha_f": [0.5]}, analyses=[other], out=tmp_path, progress=False)
    with pytest.raises(ParameterError, match=r"base Nx: 16 there, 20 now"):
        run_sweep(BASE.replace(Nx=20), {"alpha_f": [0.5]}, analyses=[EQ_FAST], out=tmp_path, progress=False)
    assert sorted(p.name for p in (tmp_path / "designs").iterdir()) == before


# -- checks before any computation, and failures -----------------------------------------------------------------

@pytest.mark.parametrize("kwargs, pattern", [
    (dict(grid={"alphaf": [1.0]}), r"'alphaf' is not a SystemSpec field; allowed: .*alpha_f"),
    (dict(grid={"alpha_f": [0.5, 200.0]}), r"alpha_f = 200 is outside the allowed range \(0, 100\]"),
    (dict(grid={"rotor": ["jeffcott", "flexible"]}), r"rotor = 'flexible' is not one of \('jeffcott', 'rigid'\)"),
    (dict(grid={"Nx": [16, 20.5]}), r"Nx must be an integer"),
    (dict(grid={"eta": [0.1, 0.1]}), r"repeated value"),
    (dict(grid={"eta": []}), r"at least one value"),
    (dict(designs=[{"eta": 0.1}, {"m_j": -1.0}]), r"designs\[1\]: m_j = -1 kg is outside the allowed range"),
    (dict(grid={"G": [0.0, 1.0]}, analyses=["cycles"]), r"cycles analysis needs an unbalanced rotor"),
    (dict(grid={"eta": [0.1]}, analyses=["whirl"]), r"'whirl' is not one of \('static', 'equilibria'"),
    (dict(grid={"eta": [0.1]}, executor="mpi"), r"executor = 'mpi' is not one of"),
    (dict(grid={"alpha_f": [0.5, 5.0]}, analyses=[Optimum()]), r"alpha_f = 5 is outside the allowed range \[0.005, 2\]"),
    (dict(grid={"eta": [0.1]}, designs=[{}]), r"either grid"),
])
def test_bad_input_raises_before_any_computation(kwargs, pattern, monkeypatch, tmp_path):
    import gfbjax.sweep._run as runner

    def forbidden(*a, **k):
        raise AssertionError("computation started")

    monkeypatch.setattr(runner, "run_serial", forbidden)
    monkeypatch.setattr(runner, "_on_dask", forbidden)
    kwargs.setdefault("analyses", [EQ])
    with pytest.raises(ParameterError, match=pattern):
        run_sweep(BASE, out=tmp_path / "out", progress=False, **kwargs)
    assert not (tmp_path / "out").exists()


def test_bad_analysis_settings_raise_on_construction():
    with pytest.raises(ParameterError, match=r"static.speeds = 60 is outside the allowed range \(0, 50\]"):
        Static(speeds=(0.2, 60.0))
    with pytest.raises(ParameterError, match=r"equilibria.end must differ"):
        Equilibria(0.3, 0.3)
    with pytest.raises(ParameterError, match=r"cycles.m = 9 is outside the allowed range \[2, 7\]"):
        Cycles(m=9)
    with pytest.raises(ParameterError, match=r"cycles: chord_tol must be a number in \[1e-06, inf\]"):
        Cycles(chord_tol=0.0)
    with pytest.raises(ParameterError, match=r"optimum.objective = 'W_cf' is not one of"):
        Optimum(objective="W_cf")
    with pytest.raises(ParameterError, match=r"energy.speeds = \[0.2, 0.2\] repeats a speed"):
        Energy(speeds=[0.2, 0.2])


def test_failed_design_is_explicit_in_a_list_sweep(tmp_path):
    # a 50 kg journal mass closes the film at Omega_bar 0.2: no static equilibrium, so no branch can start
    ds = run_sweep(BASE, designs=[{"m_j": 0.5}, {"m_j": 50.0}],
                   analyses=[Static((0.2,)), Equilibria(0.2, 0.6)], out=tmp_path, progress=False,
                   compilation_cache=False)
    assert ds.outcome.dims == ("design",)
    np.testing.assert_array_equal(ds["m_j"], [0.5, 50.0])
    assert list(ds.outcome.values) == ["ok", "partial"]
    assert ds.message.values[1].startswith("equilibria: NoSolutionError: no static equilibrium at Omega_bar = 0.2")
    assert math.isnan(float(ds.hopf_omega_bar[1])) and math.isnan(float(ds.equilibria_points[1]))
    assert str(ds.static_outcome.values[1, 0]) == "contact" and math.isnan(float(ds.static_eccentricity[1, 0]))
    assert np.isfinite(float(ds.hopf_omega_bar[0]))
    rec = json.loads(next(p for p in (tmp_path / "designs").glob("*.json")
                          if json.loads(p.read_text())["changes"] == {"m_j": 50.0}).read_text())
    assert rec["outcome"] == "partial" and "NoSolutionError" in rec["message"]


# -- dask.distributed -------------------------------------------------------------------------------------------------

def test_dask_cluster_by_address_equals_serial(cluster, serial, tmp_path):
    lc, _ = cluster
    ds = run_sweep(BASE, GRID, analyses=[EQ], scheduler=lc.scheduler_address, out=tmp_path, progress=False)
    assert ds.attrs["executor"] == "dask"
    for v in ("hopf_omega_bar", "hopf_whirl_omega", "equilibria_points", "equilibria_last_omega_bar"):
        np.testing.assert_allclose(ds[v], serial[v], rtol=1e-10, atol=0, err_msg=v)
    pids = {json.loads(p.read_text())["pid"] for p in (tmp_path / "designs").glob("*.json")}
    assert os.getpid() not in pids  # computed on the workers, not here
    # the workers run with gfbjax's XLA settings and the persistent compilation cache
    _, client = cluster
    flags = client.run(lambda: os.environ.get("XLA_FLAGS", ""))
    cache = client.run(lambda: __import__("jax").config.jax_compilation_cache_dir)
    assert all("xla_cpu_enable_concurrency_optimized_scheduler=false" in f for f in flags.values())
    assert all(c for c in cache.values())
    # with a core per worker, each worker's threads (XLA's pool included) run on its own core
    if hasattr(os, "sched_getaffinity") and len(os.sched_getaffinity(0)) >= 2:
        cores = client.run(lambda: {tuple(sorted(os.sched_getaffinity(int(t))))
                                    for t in os.listdir("/proc/self/task")})
        assert all(len(c) == 1 and len(next(iter(c))) == 1 for c in cores.values()), cores
        assert len({next(iter(c)) for c in cores.values()}) == 2, cores


def test_killed_worker_loses_no_design(cluster, serial, tmp_path):
    """kill -9 the worker holding a design while it computes: Dask reruns it elsewhere, the sweep completes."""
    import threading
    import time

    _, client = cluster
    client.wait_for_workers(2, timeout=120)
    killed: dict = {}
    records = []
    done = threading.Event()

    def kill_first_busy_worker():
        # watched from a thread, not from the records: when a record reaches the client the other designs may
        # all be finished already (the workers hold the cores, the client waits its turn)
        while not done.is_set() and not killed:
            busy = {w: [k for k in keys if str(k).startswith("gfbjax-sweep-")]
                    for w, keys in client.processing().items()}
            victim = next((w for w, keys in busy.items() if keys), None)
            if victim is not None:
                time.sleep(0.2)  # into the design
                pid = client.run(os.getpid, workers=[victim])[victim]
                killed.update(pid=pid, designs={str(k).split("-")[2] for k in busy[victim]})
                os.kill(pid, signal.SIGKILL)
            time.sleep(0.02)

    watcher = threading.Thread(target=kill_first_busy_worker, daemon=True)
    watcher.start()
    try:
        ds = run_sweep(BASE, GRID, analyses=[EQ], client=client, out=tmp_path, progress=False,
                       on_record=records.append)
    finally:
        done.set()
        watcher.join(10)
    assert killed["designs"]
    assert list(ds.outcome.values.ravel()) == ["ok"] * 4 and len(records) == 4
    for rec in records:
        if rec["key"] in killed["designs"]:
            assert rec["pid"] != killed["pid"]  # recomputed by another worker process
    for v in ("hopf_omega_bar", "hopf_whirl_omega", "equilibria_points"):
        np.testing.assert_allclose(ds[v], serial[v], rtol=1e-10, atol=0, err_msg=v)
    assert len(list((tmp_path / "designs").glob("*.json"))) == 4


# -- cycles and energy -----------------------------------------------------------------------------------------------

def test_cycles_and_energy_figures_equal_direct_analyses():
    import dataclasses as dc

    from gfbjax.analyses.cycles import continue_gfb_cycles
    from gfbjax.analyses.energy import branch_energy

    cyc = Cycles(0.36, 0.42, m=3, N=8, max_points=15, locate=False)  # locating the NS point costs ~30 s
    ds = run_sweep(BASE, designs=[{"alpha_f": 0.5}], analyses=[cyc, Energy((0.36,), m=3, N=8)], progress=False,
                   compilation_cache=False)
    spec = BASE.replace(alpha_f=0.5)
    params = spec.nondim().traced()
    br = continue_gfb_cycles(params, 0.36, 0.42, dc.replace(cyc.cont_settings(), save_states=True))
    ns = br.special[0]
    assert ns.type == "NS" and 0.36 < ns.lam < 0.42
    # stable up to the Neimark-Sacker point, unstable past it: the first loss of stability is there
    assert np.all(br.stable[br.lam < ns.lam - 1e-9]) and not np.any(br.stable[br.lam > ns.lam + 1e-9])
    row = ds.isel(design=0)
    assert str(row.cycles_first_special.values) == "NS"
    assert float(row.cycles_loss_omega_bar) == pytest.approx(ns.lam, rel=1e-9)
    assert float(row.cycles_loss_rpm) == pytest.approx(spec.rpm(ns.lam), rel=1e-9)
    assert float(row.cycles_special_count) == len(br.special)
    assert str(row.cycles_outcome.values) == str(br.outcome)
    # the branch's first point is the cycle at 0.36: its works and multipliers
    assert br.lam[0] == 0.36
    W = branch_energy(br, params)
    assert float(row.energy_W_cb[0]) == pytest.approx(W.W_cb[0], rel=1e-9)
    assert float(row.energy_W_cf[0]) == pytest.approx(W.W_cf[0], rel=1e-9)
    assert float(row.energy_W_fu[0]) == pytest.approx(W.W_fu[0], rel=1e-9)
    assert float(row.energy_max_mu[0]) == pytest.approx(np.sort(np.abs(br.multipliers[0]))[-2], rel=1e-9)
    assert float(row.energy_stable[0]) == 1.0 and bool(br.stable[0])


class _Branch:
    """The parts of a cycle branch that the cycles figures read."""

    def __init__(self, lam, stable, special=()):
        from gfbjax.cont import Outcome

        self.lam, self.stable = np.asarray(lam, float), np.asarray(stable, bool)
        self.special, self.outcome = list(special), Outcome.REACHED_END
        self.flagged = np.zeros(len(self.lam), bool)

    def __len__(self):
        return len(self.lam)


@pytest.mark.parametrize("stable, special, loss, first", [
    ([1, 1, 1, 1], [], math.nan, ""),                      # stable throughout: no loss of stability
    ([1, 1, 0, 0], [], 0.3, ""),                           # no special point: the first unstable point
    ([1, 1, 0, 0], [("PD", 0.25, 1)], 0.25, "PD"),         # a located point at the row before: its speed
    ([1, 1, 0, 0], [("NS", 0.27, 2)], 0.27, "NS"),         # a point at the first unstable row: its speed
    ([0, 0, 1, 1], [("LPC", 0.33, 3)], 0.1, "LPC"),        # unstable from the start: the start speed
])
def test_cycle_figures_of_made_up_branches(stable, special, loss, first):
    from gfbjax.cont import SpecialPoint
    from gfbjax.sweep._analyses import cycle_branch_figures

    sp = [SpecialPoint(t, lam, i, np.zeros(0), True) for t, lam, i in special]
    f = cycle_branch_figures(_Branch([0.1, 0.2, 0.3, 0.4], stable, sp), BASE)
    assert f["cycles_first_special"] == first and f["cycles_special_count"] == len(special)
    assert (math.isnan(f["cycles_loss_omega_bar"]) if math.isnan(loss) else f["cycles_loss_omega_bar"] == loss)
    assert f["cycles_stable_at_start"] == float(stable[0]) and f["cycles_last_omega_bar"] == 0.4


# -- command line and plots ------------------------------------------------------------------------------------------

def test_cli_sweep_writes_netcdf_plot_and_resumes(tmp_path, capsys):
    import xarray as xr

    from gfbjax.cli import main

    argv = ["sweep", "--nx", "16", "--nz", "2", "--grid", "alpha_f=0.5,1", "--grid", "eta=linspace(0.05,0.2,2)",
            "--analysis", "equilibria", "--start", "0.2", "--end", "0.6", "--out", str(tmp_path), "--quiet"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "4 designs" in out and "0 reused" in out
    # every row of the table names its design (a one-field grid lost its values: tested in the next test)
    assert "alpha_f=0.5 eta=0.05" in out and "alpha_f=1 eta=0.2" in out
    for name in ("sweep.nc", "sweep.png", "sweep.json", "manifest.json"):
        assert (tmp_path / name).is_file(), name
    direct = run_sweep(BASE, GRID, analyses=[Equilibria(0.2, 0.6)], progress=False, compilation_cache=False)
    with xr.open_dataset(tmp_path / "sweep.nc") as ds:
        np.testing.assert_allclose(ds.hopf_omega_bar, direct.hopf_omega_bar, rtol=1e-12)
    assert main(argv) == 0
    assert "4 reused" in capsys.readouterr().out


def test_cli_sweep_of_one_field_names_its_designs_and_plots_any_variable_it_offers(tmp_path, capsys):
    from gfbjax.cli import main
    from gfbjax.sweep.plot import numeric_variables, plot_variables

    argv = ["sweep", "--nx", "16", "--nz", "2", "--grid", "alpha_f=0.5,1", "--analysis", "equilibria",
            "--start", "0.2", "--end", "0.6", "--out", str(tmp_path), "--quiet", "--plot", "seconds"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "alpha_f=0.5 " in out and "alpha_f=1 " in out
    ds = run_sweep(BASE, {"alpha_f": [0.5]}, analyses=[EQ_FAST], progress=False, compilation_cache=False)
    assert plot_variables([EQ_FAST]) == numeric_variables(ds)


@pytest.mark.parametrize("argv, fragment", [
    (["--grid", "alphaf=1"], "--grid alphaf: unknown SystemSpec field"),
    (["--grid", "alpha_f=0.5,x"], "--grid alpha_f: expected a real number"),
    (["--grid", "alpha_f"], "--grid expects FIELD=VALUES"),
    (["--grid", "eta=0,0.1"], "eta = 0 is outside the allowed range"),
    (["--grid", "eta=linspace(0.1,0.5)"], "linspace(start, stop, count) takes 3 numbers"),
    (["--grid", "eta=0.1", "--analysis", "equilibria,wobble"], "--analysis"),
    (["--grid", "eta=0.1", "--workers", "-1"], "--workers = -1 is outside"),
    (["--grid", "eta=0.1", "--speeds", "0.2,70"], "--speeds"),
    ([], "give the designs"),
    # the figure's variable is drawn after the whole sweep: checked before it
    (["--grid", "eta=0.1", "--plot", "bogus"], "--plot 'bogus' is not a numeric result of --analysis equilibria"),
    (["--grid", "eta=0.1", "--analysis", "static", "--plot", "hopf_omega_bar"], "choose one of static_"),
    (["--grid", "eta=0.1", "--plot", "hopf_omega_bar", "--no-figures"], "with --no-figures there is none"),
])
def test_cli_bad_input_exits_2(argv, fragment, capsys, tmp_path):
    from gfbjax.cli import main

    code = main(["sweep", *argv, "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2
    assert fragment in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "o" / "designs").exists()


def test_plots_accept_axes_and_mark_failures(serial):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from gfbjax.sweep.plot import heatmap, lines, plot_sweep

    fig, (a1, a2) = plt.subplots(1, 2)
    assert heatmap(serial, "hopf_omega_bar", ax=a1) is fig
    assert lines(serial, "hopf_omega_bar", x="alpha_f", hue="eta", ax=a2) is fig
    assert a1.get_xlabel() == "alpha_f" and a1.get_ylabel() == "eta"
    assert len(a2.get_lines()) == 2
    bad = serial.copy(deep=True)
    bad["outcome"][0, 1] = "failed"
    bad["hopf_omega_bar"][0, 1] = np.nan
    f2 = plot_sweep(bad)
    crosses = [ln for ln in f2.axes[0].get_lines() if ln.get_marker() == "x"]
    assert len(crosses) == 1 and len(crosses[0].get_xdata()) == 1
    with pytest.raises(ValueError, match="var = 'outcome' is not a numeric variable"):
        heatmap(serial, "outcome")
    plt.close("all")
