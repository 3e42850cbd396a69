"""Where ``xval`` writes (issue 18, "writing files safely"): default names made safe
from a description's ``name``, no command overwriting one of its own inputs or writing
two outputs to one file, names that no XML file can carry refused where the
description is read, well-formed XML for every name that is accepted, and ``models``
refusing what ``compare`` refuses.

The expectations are the user's: a file that was there before the command is byte for
byte the same after a refusal, a refusal is one line and status 2, and XML is
whatever Python's own parser accepts.
"""

from __future__ import annotations

import hashlib
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from analytic import LinkageError, load_case
from analytic.cases import case_path
from reports.cli.paths import check_outputs, safe_stem
from reports.cli.xval import main


def _with_name(tmp_path: Path, name_toml: str, file: str = "case.toml",
               crank: str = "crank") -> Path:
    """The seed four-bar with its ``name = ...`` line (TOML text) replaced and its crank
    body renamed ``crank`` (a TOML key as written)."""
    text = case_path("seed-four-bar").read_text(encoding="utf-8")
    text = text.replace('name = "seed-four-bar"', f"name = {name_toml}", 1)
    as_string = crank if crank.startswith('"') else f'"{crank}"'
    text = text.replace("[bodies.crank]", f"[bodies.{crank}]").replace('"crank"', as_string)
    f = tmp_path / file
    f.write_text(text, encoding="utf-8")
    return f


def _digest(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("xval: error:") and err.count("\n") == 1, err
    return err


# -- default names ---------------------------------------------------------------------------

@pytest.mark.parametrize("name, stem", [
    ("../escaped_by_name", "escaped_by_name"), ("/etc/passwd", "etc_passwd"),
    ("a/b\\c", "a_b_c"), ("..", "linkage"), ("", "linkage"), (".hidden", "hidden"),
    ("fb\x01\x0b", "fb"), ("four bar (v2)", "four_bar_v2"), ("seed-four-bar", "seed-four-bar")])
def test_safe_stem(name, stem):
    assert safe_stem(name) == stem
    assert os.sep not in safe_stem(name) and not Path(safe_stem(name)).is_absolute()


def test_plot_default_name_stays_in_the_working_folder(tmp_path, monkeypatch, capsys):
    """name-escapes-folder.toml: ``xval plot FILE`` wrote ../escaped_by_name-plot.png."""
    work = tmp_path / "work"
    work.mkdir()
    f = _with_name(tmp_path, '"../escaped_by_name"')
    monkeypatch.chdir(work)
    assert main(["plot", str(f), "--samples", "12"]) == 0
    capsys.readouterr()
    assert [p.name for p in tmp_path.iterdir() if p.is_file()] == ["case.toml"]
    assert (work / "escaped_by_name-plot.png").is_file()


# -- no output over an input, no two outputs in one file -------------------------------------

@pytest.mark.parametrize("argv", [
    ["explain", "{f}", "--out", "{f}"],
    ["explain", "{f}", "--out", "{dot_f}"],
    ["explain", "{f}", "--format", "html", "--out", "{link}"],
    ["sweep", "{f}", "--csv", "{f}"],
    ["plot", "{png}", "--out", "{png}"],
    ["animate", "{html}", "--out", "{html}"],
    ["baseline", "record", "{f}", "--engine", "mujoco", "--out", "{f}"],
    ["baseline", "check", "{f}", "--junit", "{f}"],
    ["baseline", "check", "{f}", "--summary", "{dot_f}"],
    ["compare", "{f}", "--engine", "mujoco", "--junit", "{f}"],
    ["compare", "seed-four-bar", "--engine", "mujoco", "--junit", "{j}", "--summary",
     "{dot_j}"],
], ids=lambda a: " ".join(a[:3]))
def test_no_command_overwrites_its_input(tmp_path, monkeypatch, capsys, argv):
    """explain F --out F, sweep F --csv F, baseline check B --junit B, baseline record F
    --out F each overwrote their input; compare --junit F --summary F kept only the
    summary.  Each is now one line, status 2, before anything runs, and the file is
    unchanged; paths are compared as files (./F, a symbolic link), not as strings."""
    monkeypatch.chdir(tmp_path)
    f = _with_name(tmp_path, '"four-bar"')
    for other in ("case.png", "case.html"):   # a description may have any file name
        (tmp_path / other).write_bytes(f.read_bytes())
    (tmp_path / "j.xml").write_text("<keep/>")
    os.symlink(f, tmp_path / "link.toml")
    subs = {"{f}": "case.toml", "{dot_f}": "./sub/../case.toml", "{link}": "link.toml",
            "{png}": "case.png", "{html}": "case.html", "{j}": "j.xml", "{dot_j}": "./j.xml"}
    (tmp_path / "sub").mkdir()
    before = {p: _digest(p) for p in tmp_path.iterdir() if p.is_file()}
    assert main([subs.get(a, a) for a in argv]) == 2
    err = _one_line(capsys)
    assert "overwrite" in err
    assert {p: _digest(p) for p in tmp_path.iterdir() if p.is_file()} == before


def test_check_outputs_ignores_standard_output_and_builtin_names(tmp_path):
    check_outputs([("--out", "-"), ("--csv", None)], [("the case file", "seed-four-bar")])
    check_outputs([("--out", str(tmp_path / "a.md"))], [("the case file", "seed-four-bar")])
    with pytest.raises(LinkageError, match="--junit and --summary name the same file"):
        check_outputs([("--junit", str(tmp_path / "x")), ("--summary",
                                                           str(tmp_path / "." / "x"))])


def test_explicit_output_folders_are_created(tmp_path):
    """The README's CI example writes ``--out tests/baselines/engines.json``; the folder
    did not exist and record refused.  An explicitly named file now gets its folders."""
    from reports.cli.options import output_file
    target = tmp_path / "ci" / "baselines" / "engines.json"
    assert output_file(str(target)) == str(target)
    assert target.parent.is_dir() and not target.exists()


# -- names no XML can carry ---------------------------------------------------------------------

@pytest.mark.parametrize("name_toml, crank, key", [
    ('"fb\\u0001\\u000b"', "crank", "name"),        # name-control-chars.toml
    ('"fb"', '"cr\\u001bank"', "body name"),
    ('"fb\\u0085"', "crank", "name"),               # a C1 control (NEL)
])
def test_control_characters_in_names_are_refused_where_read(tmp_path, capsys, name_toml,
                                                            crank, key):
    f = _with_name(tmp_path, name_toml, crank=crank)
    with pytest.raises(LinkageError, match=f"{key} .* contains the control character U\\+"):
        load_case(str(f))
    out = tmp_path / "models"
    assert main(["models", str(f), "--out", str(out)]) == 2
    assert str(f) in _one_line(capsys)
    assert not out.exists()  # a refusal leaves no folder (issue 30)


def test_every_accepted_name_gives_well_formed_xml(tmp_path, capsys):
    """Names with XML's own special characters (and non-ASCII) are accepted: the MJCF,
    URDF and JUnit files must parse, and carry the names back unchanged."""
    name = "a<b&\"c'> \u00e9]]>--"
    crank = "cr<&>\"ank"
    f = _with_name(tmp_path, '"a<b&\\"c\'> \u00e9]]>--"', crank='"cr<&>\\"ank"')
    assert load_case(str(f)).name == name
    out = tmp_path / "models"
    assert main(["models", str(f), "--out", str(out)]) == 0
    mjcf = ET.parse(out / "case.xml").getroot()
    assert crank in [b.get("name") for b in mjcf.iter("body")]
    urdf = ET.parse(out / "case.urdf").getroot()
    assert urdf.get("name") == name and crank in [k.get("name") for k in urdf.iter("link")]
    junit = tmp_path / "j.xml"
    main(["compare", str(f), "--engine", "mujoco", "--revolutions", "1", "--samples", "8",
          "--junit", str(junit)])
    capsys.readouterr()
    assert [c.get("name") for c in ET.parse(junit).getroot().iter("testcase")] == [name]


def test_junit_text_is_cleaned_of_what_xml_cannot_hold():
    """A baseline's case name or a path may still carry control characters or a lone
    surrogate (a file name's undecodable byte): the JUnit file must stay well formed."""
    from reports.regression.ci_formats import CiCase, junit_xml
    text = junit_xml("suite \udcff\x01", [CiCase("case\x0b", "mujoco\x01", "fail",
                                                 message="m\x02", details="d\x1b")])
    root = ET.fromstring(text.encode("utf-8"))
    assert root.get("name") == "suite " and root.find(".//testcase").get("name") == "case"


# -- models refuses what compare refuses --------------------------------------------------------

def test_models_refuses_what_compare_refuses(tmp_path, capsys):
    """nano-four-bar.toml: compare refused it in one line, models let MuJoCo's
    ValueError escape.  The same one line from both."""
    text = case_path("seed-four-bar").read_text(encoding="utf-8")
    f = tmp_path / "nano.toml"
    f.write_text(text.replace('length = "mm"', 'length = "m"').replace(
        "[400, 0]", "[4e-7, 0]").replace("[100, 0]", "[1e-7, 0]").replace(
        "[300, 0]", "[3e-7, 0]").replace("[250, 0]", "[2.5e-7, 0]").replace(
        "[50, 0]", "[5e-8, 0]").replace("[150, 0]", "[1.5e-7, 0]").replace(
        "[125, 0]", "[1.25e-7, 0]").replace("[310, 230]", "[3.1e-7, 2.3e-7]"))
    load_case(str(f))   # a valid description: only MuJoCo's compiler refuses it
    assert main(["compare", str(f), "--engine", "mujoco"]) == 2
    refused = _one_line(capsys)
    assert "MuJoCo cannot compile its model" in refused
    assert main(["models", str(f), "--out", str(tmp_path / "m")]) == 2
    assert _one_line(capsys) == refused
