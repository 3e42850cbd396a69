"""MuJoCo runs of hand-written user models (sim_models.own.mujoco_own): the mapping of
the model's coordinates onto the description's tree, driven and released."""

from __future__ import annotations

import pytest

from reports.comparison.compare import compare_run
from sim_models.own import import_model
from sim_models.own.mujoco_own import run_prescribed
from sim_models.runs.engine_run import RunRequest

from . import user_models as um

pytest.importorskip("mujoco")

#: The harness's prescribed-run tolerance (reports.comparison): 1e-3 of peak.
TOL = 1e-3


@pytest.mark.parametrize("xml", [um.four_bar_xml(stiff=True),
                                 um.four_bar_xml("sites", stiff=True),
                                 um.chain_four_bar_xml()],
                         ids=["anchor", "sites", "closed-at-ground"])
def test_driven_near_hard_four_bars_pass(tmp_path, xml):
    """Near-hard connects (solref 0.002 s, solimp 0.9999): every angular acceleration,
    the drive's effort and every pin force within 1e-3 of peak over the default run
    (RunRequest), the loop closed at a ground pin (the model's tree a chain) included."""
    p = tmp_path / "m.xml"
    p.write_text(xml)
    tree, r = run_prescribed(import_model(str(p)), RunRequest())
    assert r.ok, r.reason
    worst = {c.quantity: c.normalised for c in compare_run(r)}
    assert max(worst.values()) < TOL, worst
    assert [c.name for c in tree.chords] == ["close" if "close" in xml else "O4"]


def test_driven_watt_six_bar_passes(tmp_path):
    """The two-loop six-bar with near-hard connects, driven: every angular acceleration,
    the drive's effort and every pin force within 1e-3 of peak over the default run
    (measured worst 5.0e-4, coupler.alpha); its two connects are the chords."""
    p = tmp_path / "six.xml"
    p.write_text(um.six_bar_xml())
    tree, r = run_prescribed(import_model(str(p)), RunRequest())
    assert r.ok, r.reason
    worst = {c.quantity: c.normalised for c in compare_run(r)}
    assert max(worst.values()) < TOL, worst
    assert {"B.force", "D.force", "link6.alpha"} <= set(worst)
    assert [c.name for c in tree.chords] == ["B", "D"]
