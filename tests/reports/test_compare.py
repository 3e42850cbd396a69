"""The comparison helper: normalisation by peak, location of the worst sample, NaN."""

from __future__ import annotations

import os

import numpy as np
import pytest

from reports.comparison.compare import compare


def test_normalised_by_peak_not_pointwise():
    x = np.linspace(0, 360, 361)
    ref = np.sin(np.radians(x))        # crosses zero: pointwise relative error would blow up
    tst = ref + 1e-4 * np.cos(np.radians(x))
    c = compare("s", ref, tst, x, 2e-4)
    assert c.passed and c.normalised == pytest.approx(1e-4, rel=1e-3)
    assert c.at in (0.0, 180.0, 360.0)


def test_vectors_use_euclidean_norm_and_fail_loudly():
    x = np.arange(4.0)
    ref = np.array([[3.0, 4.0], [0, 0], [0, 0], [0, 0]])
    tst = ref.copy()
    tst[2] = [0.03, 0.04]
    c = compare("F", ref, tst, x, 1e-3)
    assert not c.passed and c.max_abs == pytest.approx(0.05) and c.at == 2.0
    assert c.normalised == pytest.approx(0.01)
    assert "FAIL" in str(c)


def test_nan_is_a_failure_at_its_angle():
    x = np.arange(5.0)
    tst = np.ones(5)
    tst[3] = np.nan
    c = compare("q", np.ones(5), tst, x, 1.0)
    assert not c.passed and c.at == 3.0 and c.normalised == float("inf")
    assert not c.measured  # a failure, not a measured error
    import json
    d = json.loads(json.dumps(c.as_json(), allow_nan=False))
    assert d["max_abs"] is None and d["normalised"] is None and d["measured"] is False
    assert d["at"] == 3.0 and d["passed"] is False


def test_a_failed_run_is_strict_json_and_says_not_measured(tmp_path, capsys):
    """A run that stops (PyBullet on a 4 nm four-bar: a loop violation) fails with every
    quantity not measured: no ``Infinity`` in the JSON (RFC 8259 has none; strict
    parsers reject it) and no ``inf`` presented as an error in the table."""
    pytest.importorskip("pybullet")
    import json

    from reports.cli.xval import main
    from tests.reports.test_bad_inputs import NANOMETRE
    f = tmp_path / "nano.toml"
    f.write_text(NANOMETRE)
    code = main(["compare", str(f), "--engine", "pybullet", "--samples", "12", "--json"])
    out, _ = capsys.readouterr()

    def reject(c):
        raise AssertionError(f"non-JSON constant {c}")
    rec = json.loads(out, parse_constant=reject)[0]
    assert code == 1 and rec["run_ok"] is False and rec["verdict"] == "fail"
    gone = [c for c in rec["comparisons"] if not c["measured"]]
    assert gone and all(c["max_abs"] is None and not c["passed"] for c in gone)
    code = main(["compare", str(f), "--engine", "pybullet", "--samples", "12"])
    out, _ = capsys.readouterr()
    assert code == 1 and "not measured" in out and " inf " not in out


def test_shape_mismatch_is_an_error():
    with pytest.raises(ValueError, match="shape"):
        compare("q", np.ones(3), np.ones(4), np.arange(3.0), 1.0)


# --- engine runs: every driver motion ends in a verdict or a typed refusal (issue 8) -----

BUGS = os.path.join(os.path.dirname(os.path.dirname(__file__)), "data", "bugs")


@pytest.mark.parametrize("name", ["reversing-input.toml", "fast-accelerating.toml"])
def test_compare_any_driver_motion_ends_in_a_verdict(name, capsys):
    """Reversing and fast-accelerating inputs: status 0/1 (a verdict) or 2 (a refusal),
    never a traceback (it was ``ValueError: zero-size array``, exit 1)."""
    import os

    from reports.cli.xval import main
    path = os.path.join(BUGS, name)
    if not os.path.isfile(path):
        pytest.skip("bug reproducers not present")
    pytest.importorskip("mujoco")
    code = main(["compare", path, "--engine", "mujoco", "--samples", "12"])
    out, err = capsys.readouterr()
    assert code in (0, 1, 2), err
    assert "Traceback" not in err
    if code in (0, 1):
        assert "sampled at 12 equal times" in out and ("PASS" in out or "FAIL" in out)
    else:
        assert len(err.strip().splitlines()) == 1


def test_nothing_to_compare_is_typed():
    """A run none of whose samples can be judged raises a typed error, not a reduction
    of an empty array."""
    import dataclasses

    from analytic import LinkageError
    from reports.comparison.compare import NothingToCompare, compare_run
    from sim_models import compile_linkage
    from sim_models.runs.driven import run
    pytest.importorskip("mujoco")
    tree = compile_linkage(__import__("analytic").load_case("seed-four-bar"))
    r = run(tree, "mujoco", samples=6)
    blank = dataclasses.replace(r, alpha=np.full_like(r.alpha, np.nan))  # none reached
    with pytest.raises(NothingToCompare) as e:
        compare_run(blank)
    assert isinstance(e.value, LinkageError) and "no sample can be compared" in str(e.value)


def test_failed_verdict_near_a_singular_position_says_so():
    """A worst error 2 deg from the parallelogram's change point (180 deg: crank and
    rocker collinear with the ground, by construction of the file) is reported with the
    distance; one 40 deg away, or at a rocker's extreme angle, is not."""
    from analytic import Linkage, load_case
    from reports.comparison.compare import Comparison, near_event
    from reports.studies.speed_accuracy import load
    lk = Linkage(load("parallelogram-four-bar"))
    msg = near_event([Comparison("rocker.alpha", 1.0, 1.0, 1.0, 182.0, 1e-3, False)], lk)
    assert msg and "2 deg from the" in msg and "180 deg" in msg
    assert near_event([Comparison("rocker.alpha", 1.0, 1.0, 1.0, 140.0, 1e-3, False)],
                      lk) is None
    seed = Linkage(load_case("seed-four-bar"))  # rocker extreme at 140.43 deg: not an event
    assert near_event([Comparison("rocker.alpha", 1.0, 1.0, 1.0, 141.0, 1e-3, False)],
                      seed) is None
    # a passing verdict says nothing
    assert near_event([Comparison("rocker.alpha", 0.0, 1.0, 0.0, 182.0, 1e-3, True)],
                      lk) is None


def test_parallelogram_passes_in_both_engines():
    """Through its change points the analytic reference continues the branch the
    engines follow (issue 8): both engines pass, with no study workaround."""
    pytest.importorskip("mujoco")
    pytest.importorskip("pybullet")
    from analytic import Linkage
    if not hasattr(Linkage, "branch_crossings"):
        pytest.skip("this solver holds its dyad signs through change points")
    from reports.comparison.runs import run_comparison
    from reports.studies.speed_accuracy import load
    from sim_models import compile_linkage
    tree = compile_linkage(load("parallelogram-four-bar"))
    for eng in ("mujoco", "pybullet"):
        r, comps = run_comparison(tree, eng, None, samples=36)
        bad = [str(c) for c in comps if not c.passed and not c.quantity.endswith("[engine]")]
        assert r.ok and not bad, (eng, r.reason, bad)


def test_compare_set_and_integrator_options(capsys):
    from reports.cli.xval import main
    pytest.importorskip("mujoco")
    code = main(["compare", "seed-four-bar", "--engine", "mujoco", "--samples", "8",
                 "--integrator", "Euler", "--set", "timestep=1e-4", "--json"])
    out, err = capsys.readouterr()
    import json
    rec = json.loads(out)[0]
    assert code in (0, 1) and rec["settings_fields"]["integrator"] == "Euler"
    assert rec["settings_fields"]["timestep"] == 1e-4
    for bad, words in ((["--set", "warp=9"], "no engine here has a setting 'warp'"),
                       (["--set", "integrator=leapfrog"], "leapfrog"),
                       (["--set", "pybullet.erp=1"], "not run here")):
        code = main(["compare", "seed-four-bar", "--engine", "mujoco", *bad])
        _, err = capsys.readouterr()
        assert code == 2 and words in err and len(err.strip().splitlines()) == 1, err


def test_prismatic_normal_and_moment_are_judged():
    """Each prismatic joint's normal force and couple are judged quantities of their own:
    a run whose guide couple is displaced by 1% of the slot's force scale fails on
    ``slot.moment`` alone (the quick-return's slot carries both a normal force and a couple)."""
    pytest.importorskip("mujoco")
    import dataclasses

    from analytic import load_case
    from reports.comparison.compare import compare_run
    from sim_models.runs.driven import run
    r = run(load_case("quick-return"), "mujoco", samples=12)
    names = {c.quantity: c for c in compare_run(r)}
    for q in ("slot.normal", "slot.moment", "ram.normal", "ram.moment"):
        assert names[q].passed, names[q]
    moment = r.moment.copy()
    p = list(r.prismatic_names).index("slot")
    moment[:, p] += 1e-2 * names["slot.moment"].peak
    bad = {c.quantity: c for c in compare_run(dataclasses.replace(r, moment=moment))}
    assert not bad["slot.moment"].passed
    assert bad["slot.moment"].normalised == pytest.approx(1e-2, rel=0.05)
    assert bad["slot.normal"].passed and bad["slot.force"].passed


def test_a_failed_verdict_says_how_far_the_input_moves_per_step():
    """fast-accelerating (the crank reaches ~1150 rad/s) fails in MuJoCo at the recommended
    absolute step; the verdict's step note gives the increment per step (rate x dt, checked
    here from the run's own prescribed rates) and a quarter step, which then passes: the
    engine's step, not the model or the solver, was at fault."""
    pytest.importorskip("mujoco")
    import dataclasses
    import re

    from analytic import load_mechanism
    from reports.comparison.compare import compare_run, step_note, verdict
    from sim_models.engines.registry import make_settings
    from sim_models.runs.driven import run
    mech = load_mechanism(os.path.join(BUGS, "fast-accelerating.toml"))
    r = run(mech, "mujoco", samples=12)
    assert not verdict(compare_run(r))
    note = step_note(r, True)
    inc = float(np.max(np.abs(r.driver_velocity))) * r.timestep
    assert f"{inc:.3g} rad" in note
    dt = float(re.search(r"--timestep (\S+)", note).group(1))
    fine = make_settings("mujoco", {})
    r2 = run(mech, "mujoco", dataclasses.replace(fine, timestep=dt), samples=12)
    assert verdict(compare_run(r2))
