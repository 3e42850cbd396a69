"""``xval import``: the description written and the table printed for a hand-written
MJCF four-bar, and the refusals as one line with status 2."""

from __future__ import annotations

import pytest

from analytic.toml_io import load_mechanism
from tests.sim_models.own import user_models as um

from .cli_run import run

pytest.importorskip("mujoco")


def test_import_writes_description_and_table(tmp_path):
    xml = tmp_path / "four_bar.xml"
    xml.write_text(um.four_bar_xml())
    out = tmp_path / "four_bar.toml"
    code, text = run("import", str(xml), "--out", str(out))
    assert code == 0
    assert "equality connect 'close' (anchor)" in text and "->  [[joints]] 'close'" in text
    assert "not modelled:" not in text  # contacts off, no limits, no friction
    mech = load_mechanism(out)
    assert mech.driver.joint == "O2" and mech.ground == "world"
    head = out.read_text().split("\n\n")[0]
    assert "# Model element -> description element:" in head
    assert "normal n = (0, -1, 0)" in head


@pytest.mark.parametrize("xml, words", [
    (um.FIVE_BAR_XML, "2 degrees of freedom: joints"),
    (um.four_bar_xml(tilt=1e-3), "joint 'O4': hinge axis is tilted by 0.001 rad"),
    (um.four_bar_xml("sites", gap=0.002), "equality connect 'close' (sites 'coupler_B', "
                                          "'rocker_B', bodies 'coupler' and 'rocker'): the "
                                          "loop is open by 2 mm"),
    ("<mujoco><worldbody><body><joint/></body></mujoco>", "MuJoCo cannot read the file"),
])
def test_refusals_are_one_line(tmp_path, capsys, xml, words):
    p = tmp_path / "m.xml"
    p.write_text(xml)
    out = tmp_path / "m.toml"
    code, _ = run("import", str(p), "--out", str(out))
    err = capsys.readouterr().err
    assert code == 2 and words in err and err.count("\n") == 1, err
    assert not out.exists()


def test_out_is_not_the_model(tmp_path, capsys):
    p = tmp_path / "m.xml"
    p.write_text(um.four_bar_xml())
    code, _ = run("import", str(p), "--out", str(p))
    assert code == 2 and "overwrite the input" in capsys.readouterr().err


@pytest.mark.parametrize("command", [("import", "--out", "m.toml"), ("compare",),
                                     ("simulate", "--engine", "mujoco")])
def test_an_sdf_model_is_refused_in_one_line_at_every_door(tmp_path, capsys, monkeypatch,
                                                             command):
    """SDF has no maintained parser installed: every command that takes a user's model
    says so in one line (compare and simulate read it as a malformed TOML before)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.sdf").write_text('<sdf version="1.7"><model name="m"></model></sdf>')
    code, _ = run(command[0], "m.sdf", *command[1:])
    err = capsys.readouterr().err
    assert code == 2 and "SDF models are not read" in err and err.count("\n") == 1, err
