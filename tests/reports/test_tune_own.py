"""``xval tune MODEL.xml``: a user's own MJCF model tuned as ``xval compare MODEL.xml``
reads it.  The tuned file is judged by the other doors, independent of the search:
``xval compare TUNED.xml`` (driven) and ``xval simulate TUNED.xml`` (released) against
the exact solution of the imported description; the written file differs from the
user's only in the attributes its comments name (every other byte kept); a model the
reader refuses, and every option that does not apply to a model, is one line, status 2.

The model: the hand-written four-bar of ``tests/sim_models/own/user_models.py`` with
MuJoCo's default ``connect`` (solref 0.02 s, solimp 0.9-0.95), which fails ``xval
compare`` as written (coupler alpha ~2.9e-3 of peak, issue 32's closing note): the
search must change the loop's softness, not only the step."""

from __future__ import annotations

import json
import re

import pytest

from reports.cli.xval import main
from reports.tune.model import MARK, attribute_differences, tuned_model_text
from tests.sim_models.own import user_models as um

from .cli_run import run

pytest.importorskip("mujoco")

#: The tolerance tuned for: 1e-3 of peak, ``xval compare``'s own verdict tolerance.
TOL = 1e-3


def _worst(doc: dict) -> float:
    """The largest normalised error of the judged quantities of a verdict's JSON."""
    return max(c["normalised"] for c in doc["comparisons"]
               if c.get("status") != "not judged")


@pytest.fixture(scope="module")
def soft(tmp_path_factory):
    d = tmp_path_factory.mktemp("own")
    p = d / "soft.xml"
    p.write_text(um.four_bar_xml())
    return p


@pytest.fixture(scope="module")
def tuned(soft):
    """``xval tune soft.xml --write-model``: status, output, the written file."""
    out = soft.parent / "soft_tuned.xml"
    code, text = run("tune", str(soft), "--tolerance", str(TOL), "--budget", "10",
                     "--workers", "1", "--write-model", str(out))
    return code, text, out


def test_the_model_fails_as_written(soft):
    """The premise: the file as the user wrote it fails xval compare at TOL."""
    code, out = run("compare", str(soft), "--engine", "mujoco", "--json")
    assert code == 1
    assert _worst(json.loads(out)[0]) > TOL


def test_tuned_model_passes_compare_at_the_tolerance(tuned):
    """The written file, given to xval compare with no option (its own settings), passes:
    every judged quantity within TOL of peak against the exact description."""
    code, text, out = tuned
    assert code == 0, text
    assert "verification (a fresh run): PASS" in text
    assert "read back by MuJoCo: the file carries the verified settings" in text
    code, js = run("compare", str(out), "--engine", "mujoco", "--json")
    assert code == 0
    assert _worst(json.loads(js)[0]) <= TOL


def _named(text: str) -> set[tuple[str, str]]:
    return {(m.group(1), m.group(2))
            for m in re.finditer(rf"<!-- {re.escape(MARK)} (\S+) (\w+): ", text)}


def test_tuned_model_differs_only_in_the_named_attributes(soft, tuned):
    """Parsed, the two files differ exactly in the attributes the comments name, and the
    loop's softness is among them (the step alone cannot pass: see the module); as
    text, with the added comment lines removed, only the lines of changed elements
    differ."""
    _c, _t, out = tuned
    a, b = soft.read_text(), out.read_text()
    diffs = {(p, k) for p, k, _x, _y in attribute_differences(a, b)}
    assert diffs == _named(b)
    assert {k for _p, k in diffs} & {"solref", "solimp"}
    kept = [ln for ln in b.splitlines() if MARK not in ln]
    changed = [(x, y) for x, y in zip(a.splitlines(), kept, strict=True) if x != y]
    assert len(kept) == len(a.splitlines())
    assert {("<option" in x or "<connect" in x) for x, _y in changed} == {True}


def test_free_tuned_model_passes_simulate(soft, tmp_path):
    """Released (--free, 0.5 s): the written file passes xval simulate at TOL of scale."""
    out = tmp_path / "free.xml"
    code, text = run("tune", str(soft), "--free", "--duration", "0.5", "--tolerance",
                     str(TOL), "--budget", "8", "--workers", "1", "--write-model", str(out))
    assert code == 0, text
    code, js = run("simulate", str(out), "--engine", "mujoco", "--duration", "0.5",
                   "--json")
    v = json.loads(js)["verdicts"][0]
    assert code == 0
    assert max(c["normalised"] for c in v["comparisons"] if c["measured"]) <= TOL


def test_writer_keeps_every_other_byte():
    """A model written by hand (comments, single quotes, `` />``, no <option>, two
    loops): the tuned text with its comment lines removed equals the original with only
    the attribute values changed and the new <option> added."""
    xml = ("<?xml version='1.0'?>\n<!-- mine -->\n<mujoco model='m'>\n"
           "  <worldbody><body name='a'><joint name='j'/><geom size='.1'/>"
           "<site name='s1'/></body><site name='s2' /></worldbody>\n"
           "  <equality>\n    <connect name='c' site1='s1' site2='s2' solref='0.02 1' />\n"
           "    <!-- second loop -->\n    <weld body1='a'/>\n  </equality>\n</mujoco>\n")
    text, changes = tuned_model_text(xml, {"solref": (0.002, 1.0), "timestep": 1e-3},
                                     {"solref": "stiffer", "timestep": "finer"})
    assert {(c.path, c.attribute) for c in changes} == {
        ("equality/connect[c]", "solref"), ("equality/weld", "solref"), ("option", "timestep")}
    kept = "\n".join(ln for ln in text.splitlines() if MARK not in ln) + "\n"
    expect = xml.replace("solref='0.02 1'", "solref='0.002 1'").replace(
        "<weld body1='a'/>", "<weld body1='a' solref=\"0.002 1\"/>").replace(
        "<mujoco model='m'>", "<mujoco model='m'>\n  <option timestep=\"0.001\"/>")
    assert kept == expect


# ============================================================================ bad input
@pytest.mark.parametrize("argv, says", [
    (["--engine", "pybullet"], "--engine"),
    (["--out", "x.json"], "--out"),
    (["--tolerance", "0"], "--tolerance"),
    (["--quantity", "speed"], "--quantity"),
])
def test_bad_option_with_a_model_is_one_line(soft, argv, says, capsys, tmp_path,
                                             monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["tune", str(soft), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and says in err
    assert not (tmp_path / "x.json").exists()


def test_refused_model_is_its_readers_one_line(tmp_path, capsys):
    """The five-bar (two degrees of freedom): the importer's line, naming the file."""
    p = tmp_path / "five.xml"
    p.write_text(um.FIVE_BAR_XML)
    assert main(["tune", str(p), "--budget", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "2 degrees of freedom" in err and str(p) in err


def test_urdf_and_model_options_elsewhere_are_one_line(tmp_path, capsys):
    u = tmp_path / "m.urdf"
    u.write_text(um.four_bar_urdf())
    for argv, says in ((["tune", str(u)], "URDF"),
                       (["tune", "seed-four-bar", "--driver", "O2", "--engine", "mujoco"],
                        "--driver"),
                       (["tune", "seed-four-bar"], "--engine")):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and says in err


def test_missing_model_and_standard_output_are_one_line(tmp_path, capsys, monkeypatch):
    """A model file that is not there is named as a missing file (not as an unknown
    built-in case); '-' as a written file is refused before any run."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.xml").write_text(um.four_bar_xml())
    for argv, says in ((["tune", "nothere.xml"], "no such file 'nothere.xml'"),
                       (["tune", "m.xml", "--write-model", "-"], "--write-model")):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and says in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.xml"]


def test_read_back_names_a_setting_the_file_does_not_carry(soft):
    """The read-back check of --write-model: the user's file as written does not carry a
    stiffer solref or a shorter step, and the check names both (file / run)."""
    from reports.tune.measure import TuneCase
    from reports.tune.own import read_back
    diff = read_back(str(soft), TuneCase(str(soft)), {"solref": (0.005, 1.0),
                                                      "timestep": 2.5e-4})
    assert any(d.startswith("close.solref: (0.02,1) / (0.005,1)") for d in diff), diff
    assert "timestep: 0.0005 / 0.00025" in diff
    assert read_back(str(soft), TuneCase(str(soft)), {}) == []


def test_driven_floor_is_the_drives_armature(monkeypatch):
    """What the no-pass line of a driven user model blames: at xval compare's drive
    (armature DRIVE_RATIO = 1e6 times the driver's inertia) halving the step leaves the
    worst error of docs/examples/user-four-bar.xml above STEP_MATTERS of itself (it sits
    at ~3e-4 of peak), while with a 10x stiffer drive the same halving cuts it by more
    than 2: the drive, not the file's settings, sets the floor; the line says so."""
    from pathlib import Path

    import sim_models.own.mujoco_own as mo
    from reports.comparison.compare import compare_run
    from reports.comparison.quantities import judged
    from reports.tune.measure import TuneCase
    from reports.tune.search import STEP_MATTERS
    from reports.tune.tune import tune
    from sim_models.own import import_model
    model = str(Path(__file__).resolve().parents[2] / "docs" / "examples" /
                "user-four-bar.xml")
    imp = import_model(model)

    def worst(step):
        _tree, r = mo.run_prescribed(imp, None, step)
        return max(c.normalised for c in judged(compare_run(r)))

    assert mo.DRIVE_RATIO == 1e6
    assert worst(2.5e-4) / worst(5e-4) > STEP_MATTERS
    monkeypatch.setattr(mo, "DRIVE_RATIO", 1e7)
    assert worst(2.5e-4) / worst(5e-4) < 0.5
    monkeypatch.undo()
    res = tune(TuneCase(model), "mujoco", 1e-4, budget=1, pool=False, knob_limit=0,
               verify=False)
    assert res.answer is None
    assert "an armature of 1e+06 times the driver's inertia" in res.limit_text


def test_a_file_not_in_utf8_is_one_line_at_every_door(tmp_path, capsys):
    """An MJCF saved as ISO-8859-1 with an accented joint name: MuJoCo keeps the name's
    byte 0xe9, which is not UTF-8; compare and tune refused it with a UnicodeDecodeError
    traceback before (the importer decoded the names); now one line naming the file and
    the byte, status 2."""
    text = um.four_bar_xml().replace('"O4"', '"O\u00e9"')
    p = tmp_path / "latin.xml"
    p.write_bytes(text.replace("<mujoco", '<?xml version="1.0" encoding="ISO-8859-1"?>\n'
                               "<mujoco", 1).encode("latin-1"))
    for argv in (["compare", str(p), "--engine", "mujoco"], ["tune", str(p)]):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "not UTF-8" in err and str(p) in err
        assert "0xe9" in err


def test_write_model_refuses_a_root_other_than_mujoco(tmp_path):
    """MuJoCo also reads a URDF named .xml: --write-model cannot edit it as MJCF, and says
    so naming the file (the command asks this before the search)."""
    from reports.tune.measure import TuneCase
    from reports.tune.model import ModelWriteError
    from reports.tune.own import tuned_text
    p = tmp_path / "robot.xml"
    p.write_text(um.four_bar_urdf())
    with pytest.raises(ModelWriteError, match=r"robot\.xml: not an MJCF model: the root "
                                              r"element is <robot>"):
        tuned_text(TuneCase(str(p)), {}, {}, "")
