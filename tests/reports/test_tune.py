"""``xval tune``: the tuned settings meet the tolerance (checked by a fresh verdict run,
independent of the search's own runs), the settings file and the tuned MJCF carry them
to the other doors, bad input is one line with status 2, and the search is
reproducible.  Small searches: the seed four-bar, prescribed, a few knobs, serial."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET

import pytest

from analytic import load_case
from reports.cli.xval import main
from reports.comparison.quantities import judged
from reports.comparison.runs import run_verdict
from reports.tune import TuneCase, tune
from reports.tune.model import MARK, attribute_differences, tuned_model_text
from sim_models import compile_linkage
from sim_models.engines.registry import available_engines

from ..sim_models.engines.test_settings_ranges import ENGINES as RANGE_ENGINES
from ..sim_models.engines.test_settings_ranges import IMPOSSIBLE

#: The tolerance of the per-engine tests: 1e-3 of peak, the report's first column.
TOL = 1e-3
CASE = "seed-four-bar"
ENGINES = [e for e in ("mujoco", "pybullet", "exudyn", "pinocchio")
           if e in available_engines()]


def _worst(tree, engine: str, settings) -> float:
    """The largest normalised error of a fresh verdict run at ``settings`` (the run and
    comparison of ``xval compare``, not the search's)."""
    v = run_verdict(tree, engine, settings)
    assert v.run.ok, v.run.reason
    return max(c.normalised for c in judged(v.comparisons))


@pytest.mark.parametrize("engine", ENGINES)
def test_tuned_settings_meet_the_tolerance(engine):
    """The answer of a small search (the step and one more knob, serial) passes at
    ``TOL`` in a fresh run; it is no more expensive in steps than the recommended run."""
    res = tune(TuneCase(CASE), engine, TOL, budget=15, pool=False, knob_limit=1,
               verify=False)
    assert res.answer is not None, res.limit_text
    tree = compile_linkage(load_case(CASE))
    assert _worst(tree, engine, res.settings) <= TOL
    assert res.answer.m.unit_steps <= res.recommended.m.unit_steps
    assert res.knob_text.startswith(f"{engine}: ")


def test_same_seed_and_budget_same_answer():
    """Two searches with the same seed and budget give the same settings (the ranking is
    by steps and cost classes, not by raw timings)."""
    a = tune(TuneCase(CASE), "mujoco", TOL, budget=10, pool=False, knob_limit=2,
             verify=False, seed=3)
    b = tune(TuneCase(CASE), "mujoco", TOL, budget=10, pool=False, knob_limit=2,
             verify=False, seed=3)
    assert a.answer is not None and b.answer is not None
    assert (a.answer.family, a.answer.steps) == (b.answer.family, b.answer.steps)
    assert a.settings == b.settings


def test_no_setting_reaches_an_impossible_tolerance():
    """1e-12 of peak is below what the step search reaches within a tiny budget: no
    answer, and the message says the best reached and what limits it."""
    res = tune(TuneCase(CASE), ENGINES[-1], 1e-12, budget=1, pool=False, knob_limit=0,
               verify=False)
    assert res.answer is None
    assert res.limit_text.startswith("best reached ")
    assert "limit:" in res.limit_text


# ============================================================================ the command
@pytest.fixture(scope="module")
def tuned_files(tmp_path_factory):
    """``xval tune`` on the seed four-bar for MuJoCo: its status, settings file and
    tuned model."""
    d = tmp_path_factory.mktemp("tune")
    out, xml = d / "mj.json", d / "mj.xml"
    code = main(["tune", CASE, "--engine", "mujoco", "--budget", "4", "--workers", "1",
                 "--out", str(out), "--write-model", str(xml)])
    return code, out, xml


def test_command_writes_a_settings_file_compare_accepts(tuned_files, capsys):
    code, out, _ = tuned_files
    assert code == 0
    doc = json.loads(out.read_text())
    assert doc["mode"] == "run" and "mujoco" in doc["engines"]
    assert main(["compare", CASE, "--engine", "mujoco", "--settings", str(out)]) == 0
    assert "PASS" in capsys.readouterr().out


def _comment_changes(text: str) -> set[tuple[str, str]]:
    return {(m.group(1), m.group(2))
            for m in re.finditer(rf"<!-- {re.escape(MARK)} (\S+) (\w+): ", text)}


def test_tuned_model_differs_only_in_the_named_attributes(tuned_files):
    """Parse the original model and the tuned one: every attribute that differs is named
    in a comment, and every comment names one that differs."""
    from sim_models.builders.mjcf import MujocoSettings
    from sim_models.builders.viewer_model import viewer_xml
    _, _, xml = tuned_files
    text = xml.read_text()
    original = viewer_xml(load_case(CASE), MujocoSettings())
    diffs = {(p, a) for p, a, _x, _y in attribute_differences(original, text)}
    assert diffs  # the tuned step differs from the recommended one
    assert diffs == _comment_changes(text)


def test_tuned_model_loads_and_passes_compare_with_its_own_settings(tuned_files):
    """MuJoCo loads the written file and steps it without a warning; the settings read
    back from its own attributes (option, equality) pass a fresh verdict at 1e-3."""
    import mujoco
    _, _, xml = tuned_files
    m = mujoco.MjModel.from_xml_path(str(xml))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    for _ in range(200):
        mujoco.mj_step(m, d)
    assert all(w.number == 0 for w in d.warning)
    root = ET.parse(xml).getroot()
    opt, eq = root.find("option"), root.find("equality")[0]
    own = {"timestep": float(opt.get("timestep")), "integrator": opt.get("integrator"),
           "solref": tuple(float(x) for x in eq.get("solref").split()),
           "tolerance": float(opt.get("tolerance"))}
    if eq.get("solimp"):
        own["solimp"] = tuple(float(x) for x in eq.get("solimp").split()) + \
            (0.001, 0.5, 2.0)[len(eq.get("solimp").split()) - 2:]
    from sim_models.engines.registry import make_settings
    tree = compile_linkage(load_case(CASE))
    assert _worst(tree, "mujoco", make_settings("mujoco", own)) <= TOL


def test_model_text_changes_only_named_attributes_of_any_mjcf():
    """The writer works on any MJCF text (a user's own model): an <option> is added
    where there is none, every <equality> constraint gets the loop's settings."""
    xml = ('<mujoco model="m"><worldbody><body name="a"><joint name="j"/>'
           '<geom size="0.1"/><site name="s1"/></body><site name="s2"/></worldbody>'
           '<equality><connect name="c" site1="s1" site2="s2"/></equality></mujoco>')
    text, changes = tuned_model_text(xml, {"solref": (-100.0, -20.0), "timestep": 1e-3},
                                     {"solref": "stiffer", "timestep": "finer"})
    assert {(c.path, c.attribute) for c in changes} == {("equality/connect[c]", "solref"),
                                                       ("option", "timestep")}
    assert _comment_changes(text) == {("equality/connect[c]", "solref"),
                                      ("option", "timestep")}
    root = ET.fromstring(text)
    assert root.find("equality/connect").get("solref") == "-100 -20"


# ============================================================================ bad input
@pytest.mark.parametrize("argv, says", [
    (["--tolerance", "0"], "--tolerance"),
    (["--tolerance", "nan"], "--tolerance"),
    (["--tolerance", "2"], "--tolerance"),
    (["--budget", "0"], "--budget"),
    (["--budget", "-5"], "--budget"),
    (["--quantity", "speed"], "--quantity"),
    (["--duration", "3"], "--duration"),
])
def test_bad_tune_input_is_one_line_status_2(argv, says, capsys):
    assert main(["tune", CASE, "--engine", "mujoco", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err


def test_write_model_needs_mujoco(capsys, tmp_path):
    assert main(["tune", CASE, "--engine", "pybullet", "--write-model",
                 str(tmp_path / "x.xml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--write-model" in err
    assert not (tmp_path / "x.xml").exists()


@pytest.mark.parametrize("content, says", [
    ("{", "not valid JSON"),
    ('{"xval_settings": 1, "mode": "run", "engines": {"mujoco": {"timestep": -1}}}',
     "'timestep'"),
    ('{"xval_settings": 1, "mode": "run", "engines": {"mujoco": {"nope": 1}}}', "'nope'"),
    ('{"xval_settings": 1, "mode": "free", "engines": {"mujoco": {}}}', "'free' settings"),
    ('{"xval_settings": 1, "mode": "run", "engines": {"warp9": {}}}', "warp9"),
    ('{"mode": "run"}', "not an xval settings file"),
    ('{"xval_settings": 1, "mode": "run", "engines": {"mujoco": {"timestep": NaN}}}',
     "NaN"),
])
def test_bad_settings_file_is_one_line_status_2(content, says, tmp_path, capsys):
    f = tmp_path / "s.json"
    f.write_text(content)
    assert main(["compare", CASE, "--engine", "mujoco", "--settings", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err and str(f) in err


def test_settings_file_and_an_option_may_not_both_set_a_key(tmp_path, capsys):
    f = tmp_path / "s.json"
    f.write_text('{"xval_settings": 1, "mode": "run", "engines": {"mujoco": '
                 '{"timestep": 0.001}}}')
    assert main(["compare", CASE, "--engine", "mujoco", "--settings", str(f),
                 "--set", "timestep=2e-3"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "both set" in err


def test_pytest_fixture_settings_accepts_a_file(tmp_path):
    """The fixtures' ``settings=`` takes a settings file's path (the run cache's
    ``settings_of``) with the same checks."""
    from reports.comparison.settings_file import SettingsFileError
    from reports.regression.run_cache import settings_of
    f = tmp_path / "s.json"
    f.write_text('{"xval_settings": 1, "mode": "run", "engines": {"mujoco": '
                 '{"timestep": 0.001, "integrator": "Euler"}}}')
    s = settings_of("mujoco", str(f))
    assert (s.timestep, s.integrator) == (0.001, "Euler")
    f.write_text('{"xval_settings": 1, "mode": "run", "engines": {"mujoco": '
                 '{"iterations": 0}}}')
    with pytest.raises(SettingsFileError, match="iterations"):
        settings_of("mujoco", str(f))


@pytest.mark.parametrize("engine, key, value, words", [
    pytest.param(*r, id=f"{r[0]}.{r[1]}={r[2]}") for r in IMPOSSIBLE if r[0] in RANGE_ENGINES])
def test_settings_file_door_has_the_ranges_of_set(engine, key, value, words, tmp_path, capsys,
                                                  monkeypatch):
    """Every impossible value of the ranges table (the one --set is checked against), in
    a settings file: one line naming the file, engine and key, status 2, no engine run."""
    import reports.comparison.runs as vr
    monkeypatch.setattr(vr, "run_verdict", lambda *a, **k: pytest.fail("an engine ran"))
    f = tmp_path / "s.json"
    f.write_text(json.dumps({"xval_settings": 1, "mode": "run",
                             "engines": {engine: {key: value}}}))
    assert main(["compare", CASE, "--engine", engine, "--settings", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err and f"engine {engine!r} key {key!r}" in err


def test_simulate_refuses_a_prescribed_settings_file(tmp_path, capsys):
    """A settings file of prescribed runs given to the free runs: one line, status 2."""
    f = tmp_path / "s.json"
    f.write_text('{"xval_settings": 1, "mode": "run", "engines": {"mujoco": {}}}')
    assert main(["simulate", CASE, "--duration", "0.1", "--engine", "mujoco",
                 "--settings", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'run' settings" in err


def test_an_answer_read_from_a_tighter_search_meets_its_tolerance():
    """The quick report reads the 1e-3 row from the 1e-4 search's runs: that answer
    passes 1e-3 in a fresh verdict run and costs no more steps than the 1e-4 one."""
    from reports.tune.tune import retarget
    res = tune(TuneCase(CASE), "mujoco", 1e-4, budget=5, pool=False, knob_limit=0,
               verify=False)
    tight = res.answer.steps
    loose = retarget(res, TOL)
    assert loose.answer is not None and loose.answer.steps <= tight
    tree = compile_linkage(load_case(CASE))
    assert _worst(tree, "mujoco", loose.settings) <= TOL
