"""Checkpoints: a continuation interrupted and resumed from its folder gives the same branch as an uninterrupted
run (points, multipliers, special points), an ended branch is returned as stored, and a folder of another
continuation is refused."""
import jax.numpy as jnp
import numpy as np
import pytest

from gfbjax.cont import (Checkpoint, CheckpointError, CycleProblem, CycleSettings, EquilibriumProblem,
                         EquilibriumSettings, Outcome, continue_cycles, continue_equilibria, hopf_point,
                         start_from_hopf)
from cont_systems import stuart_landau_sub, two_hopf_pairs

W = 2.0
EQ = EquilibriumSettings(ds=0.1, ds_max=0.2, lam_max=3.0)
CY = CycleSettings(m=4, N=10, ds=0.05, ds_max=0.2, max_points=14, lam_min=-0.4, lam_max=0.3, save_states=True)


def _interrupt_at(k):
    """A callback that interrupts at the first row with index >= k."""
    def cb(i, rec):
        if i >= k:
            raise KeyboardInterrupt
    return cb


def _same(a, b, tol):
    assert len(a) == len(b)
    for key in ("lam", "period", "l2", "xmax", "xmin", "stable", "ds", "tangent_lam"):
        np.testing.assert_allclose(getattr(a, key), getattr(b, key), rtol=tol, atol=tol, err_msg=key)
    np.testing.assert_allclose(a.multipliers, b.multipliers, rtol=tol, atol=tol)
    assert [(s.type, s.located) for s in a.special] == [(s.type, s.located) for s in b.special]
    np.testing.assert_allclose([s.lam for s in a.special], [s.lam for s in b.special], rtol=tol, atol=tol)


def test_equilibria_resume_equals_uninterrupted(tmp_path):
    prob = EquilibriumProblem(two_hopf_pairs, 4)
    whole = continue_equilibria(prob, EQ, np.zeros(4), 0.0)
    assert [round(h.lam, 9) for h in whole.special_of("HOPF")] == [1.0, 2.0]
    first = continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path, callback=_interrupt_at(6))
    assert first.outcome is Outcome.INTERRUPTED and len(first) < len(whole)
    assert [h.lam for h in first.special_of("HOPF")] == [1.0]
    assert not (tmp_path / "end.json").exists()
    seen = []
    resumed = continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path,
                                  callback=lambda i, rec: seen.append(i))
    assert resumed.outcome is whole.outcome
    assert seen[0] == len(first) - 1 and seen[-1] == len(whole) - 1  # resumes at the last point written
    _same(resumed, whole, 1e-12)


def test_cycles_resume_through_a_fold(tmp_path):
    """Subcritical Hopf: the branch turns at the fold of cycles lam = -1/4; interrupted before the fold and
    resumed, it finds the same fold and the same points."""
    eq = EquilibriumProblem(stuart_landau_sub, 2, jnp.asarray(W))
    hp = hopf_point(eq, continue_equilibria(eq, EquilibriumSettings(ds=0.07, max_points=8), np.zeros(2), -0.3))
    prob = CycleProblem(stuart_landau_sub, 2, jnp.asarray(W))
    whole = continue_cycles(prob, CY, start_from_hopf(hp, CY))
    lpc = whole.special_of("LPC")
    assert len(lpc) == 1 and abs(lpc[0].lam + 0.25) < 1e-8, whole.special
    k = lpc[0].index - 2
    part = continue_cycles(prob, CY, start_from_hopf(hp, CY), checkpoint=tmp_path, callback=_interrupt_at(k))
    assert part.outcome is Outcome.INTERRUPTED and part.special == []
    resumed = continue_cycles(prob, CY, start_from_hopf(hp, CY), checkpoint=tmp_path)
    _same(resumed, whole, 1e-10)
    np.testing.assert_allclose(resumed.states["xm"], whole.states["xm"], atol=1e-10)
    # the special point's own state comes back too
    np.testing.assert_allclose(resumed.special_states[0]["T"], whole.special_states[0]["T"], rtol=1e-10)


def test_ended_branch_is_returned_as_stored(tmp_path):
    prob = EquilibriumProblem(two_hopf_pairs, 4)
    done = continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path)
    assert done.outcome is Outcome.REACHED_END and (tmp_path / "end.json").exists()
    calls = []
    again = continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path, callback=lambda *a: calls.append(a))
    assert calls == [] and again.outcome is Outcome.REACHED_END and again.message == done.message
    _same(again, done, 0.0)


def test_folder_of_another_continuation_is_refused(tmp_path):
    prob = EquilibriumProblem(two_hopf_pairs, 4)
    continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=Checkpoint(tmp_path, {"system": "a"}),
                        callback=_interrupt_at(3))
    with pytest.raises(CheckpointError, match="settings"):
        continue_equilibria(prob, EquilibriumSettings(ds=0.05, lam_max=3.0), np.zeros(4), 0.0,
                            checkpoint=Checkpoint(tmp_path, {"system": "a"}))
    with pytest.raises(CheckpointError, match="identity.system"):
        continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=Checkpoint(tmp_path, {"system": "b"}))


def test_a_partly_written_step_is_ignored(tmp_path):
    """A kill during a write leaves only a temporary file (written, then renamed): it is not read."""
    prob = EquilibriumProblem(two_hopf_pairs, 4)
    whole = continue_equilibria(prob, EQ, np.zeros(4), 0.0)
    continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path, callback=_interrupt_at(5))
    steps = sorted(tmp_path.glob("step_*.npz"))
    (tmp_path / f"step_{len(steps):05d}.npz.tmp").write_bytes(b"PK\x03\x04 truncated")
    resumed = continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path)
    _same(resumed, whole, 1e-12)


def test_folder_of_another_problem_or_start_is_refused(tmp_path):
    """The engine's own identity: another vector field, other fixed parameters or another start in the same
    folder is refused, never handed the stored branch."""
    def shifted(x, lam, args):
        return jnp.array([args + lam * x[0] - x[0] ** 3])

    def other(x, lam, args):
        return jnp.array([lam - x[0] ** 2])

    st = EquilibriumSettings(ds=0.05, lam_min=-1.0, lam_max=1.0)
    continue_equilibria(EquilibriumProblem(shifted, 1, 1e-4), st, np.array([1e-4]), -1.0, checkpoint=tmp_path,
                        callback=_interrupt_at(5))
    for prob, x0 in ((EquilibriumProblem(shifted, 1, 0.05), [1e-4]), (EquilibriumProblem(other, 1), [1e-4]),
                     (EquilibriumProblem(shifted, 1, 1e-4), [2e-4])):
        with pytest.raises(CheckpointError, match="identity"):
            continue_equilibria(prob, st, np.array(x0), -1.0, checkpoint=tmp_path)


def test_folder_of_an_older_format_is_refused_with_its_reason(tmp_path):
    """A folder written before the test functions changed orientation (format version 1) would fake a sign change
    at the first resumed step: it is refused, and the message says why (not "another continuation")."""
    import json

    prob = EquilibriumProblem(two_hopf_pairs, 4)
    continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path, callback=_interrupt_at(3))
    journal = tmp_path / "journal.json"
    head = json.loads(journal.read_text())
    head["version"] = 1
    journal.write_text(json.dumps(head))
    with pytest.raises(CheckpointError, match="format version 1"):
        continue_equilibria(prob, EQ, np.zeros(4), 0.0, checkpoint=tmp_path)


@pytest.mark.parametrize("k", range(3, 9))
def test_resume_keeps_the_event_refinement_count(tmp_path, k):
    """With event_refine = 1 the refinement budget spans several steps (the count runs until the event is passed);
    a branch interrupted in between must resume with the same count.  Before, the count restarted at 0 after a
    resume, and the resumed branch found two Hopf points that the uninterrupted one did not (review of this
    issue): here every interruption point gives the uninterrupted branch."""
    import sys
    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from test_cont_events import opposite_hopf_pairs

    prob = EquilibriumProblem(opposite_hopf_pairs, 4, jnp.asarray(0.03))
    st = EquilibriumSettings(ds=0.2, ds_max=0.2, lam_max=1.5, event_refine=1)
    whole = continue_equilibria(prob, st, np.zeros(4), 0.05)
    first = continue_equilibria(prob, st, np.zeros(4), 0.05, checkpoint=tmp_path / "ck", callback=_interrupt_at(k))
    assert first.outcome is Outcome.INTERRUPTED
    resumed = continue_equilibria(prob, st, np.zeros(4), 0.05, checkpoint=tmp_path / "ck")
    _same(resumed, whole, 1e-12)


@pytest.mark.parametrize("k", [3, 6, 11])
def test_resume_keeps_the_chord_test_history(tmp_path, k):
    """With ``chord_tol`` the next step depends on the last three step end points; they are rows of the branch,
    named in the checkpoint, so that a resumed branch takes the same steps (every one checked, ds included)."""
    from test_cont_steps import step_curve, K

    st = EquilibriumSettings(ds=0.01, ds_max=0.5, lam_min=-1.0, lam_max=1.0, chord_tol=1e-3)
    prob = EquilibriumProblem(step_curve, 1)
    whole = continue_equilibria(prob, st, np.array([np.tanh(-K)]), -1.0)
    first = continue_equilibria(prob, st, np.array([np.tanh(-K)]), -1.0, checkpoint=tmp_path / "ck",
                                callback=_interrupt_at(k))
    assert first.outcome is Outcome.INTERRUPTED
    resumed = continue_equilibria(prob, st, np.array([np.tanh(-K)]), -1.0, checkpoint=tmp_path / "ck")
    _same(resumed, whole, 1e-12)
