"""``xval tune --json``: one strict-JSON object whose numbers are the text output's (the
same result printed both ways: every number the text shows, at the digits it shows
them, equals the JSON's), whose keys are those the help lists, and whose no-pass answer
is null with the limit stated (status 1)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from reports.cli.tune import JSON_KEYS
from reports.tune import TuneCase, output, tune

from .cli_run import run

pytest.importorskip("mujoco")

MODEL = str(Path(__file__).resolve().parents[2] / "docs" / "examples" / "user-four-bar.xml")


@pytest.fixture(scope="module")
def res():
    return tune(TuneCase(MODEL), "mujoco", 1e-3, budget=4, pool=False)


def _g(x: float, digits: int = 3) -> float:
    return float(f"{x:.{digits}g}")


def test_json_numbers_are_the_texts(res):
    text = output.full_text(res)
    doc = json.loads(json.dumps(output.json_document(res), allow_nan=False))
    m = re.search(r"search: (\d+) runs, (\S+) s CPU of a (\S+) s budget", text)
    assert int(m.group(1)) == doc["search"]["runs"] == len(doc["candidates"])
    assert float(m.group(2)) == _g(doc["search"]["cpu_s"])
    assert float(m.group(3)) == doc["budget_s"]
    m = re.search(r"answer: (\d+) steps per revolution; changed: (.*)", text)
    assert int(m.group(1)) == doc["answer"]["steps_per_unit"]
    for k, (a, b) in doc["answer"]["changed"].items():
        assert f"{k} {a:.4g} -> {b:.4g}" in m.group(2) if isinstance(a, float) else \
            f"{k} {a} -> {b}" in m.group(2)
    m = re.search(r"verification \(a fresh run\): (PASS|FAIL), worst (\S+) (\S+) of peak "
                  r"\(tolerance (\S+)\)", text)
    v = doc["verification"]
    assert (m.group(1) == "PASS") == v["passed"] == doc["passed"]
    assert m.group(2) == v["quantity"] and float(m.group(3)) == _g(v["error"])
    assert float(m.group(4)) == doc["tolerance"] and v["error"] <= doc["tolerance"]
    m = re.search(r"CPU: (\S+) ms per revolution .* recommended (\S+) ms: ratio (\S+) ",
                  text)
    assert float(m.group(1)) == _g(v["cpu_s"] * 1e3)
    assert float(m.group(2)) == _g(v["recommended_cpu_s"] * 1e3)
    assert float(m.group(3)) == _g(v["cpu_ratio"])
    m = re.search(r"ms against \S+ ms, ratio (\S+)", text)
    assert float(m.group(1)) == _g(v["stepping_only_ratio"])
    assert f"knob: {doc['knob']}" in text and doc["limit"] is None
    # the candidates: the answer is one of them, the front rows are the text's table
    (ans,) = [c for c in doc["candidates"] if c["answer"]]
    assert ans["steps_per_unit"] == doc["answer"]["steps_per_unit"] and ans["passed"]
    front = [c for c in doc["candidates"] if c["on_front"]]
    table = [ln for ln in text.split("Pareto front")[1].split("next-cheapest")[0]
             .splitlines()[2:] if not ln.startswith("the answer is not on the front")]
    assert len(table) == min(12, len(front))
    for row, c in zip(table, front, strict=False):
        cells = row.split()
        assert int(cells[-4]) == c["steps_per_unit"]
        assert float(cells[-3]) == _g(c["model_cost_s"] * 1e3)
        assert float(cells[-2]) == _g(c["error"], 2)
        assert cells[-1] == ("pass" if c["passed"] else "fail")


def test_json_keys_are_the_helps(res):
    """Every top-level key and every key of answer, verification, search and a candidate
    is named in the help epilog (JSON_KEYS)."""
    doc = output.json_document(res)
    keys = set(doc) | set(doc["answer"]) | set(doc["verification"]) | \
        set(doc["search"]) | set(doc["candidates"][0])
    words = set(re.findall(r"[a-z_]+", JSON_KEYS))
    assert keys <= words, keys - words


def test_cli_json_is_one_object_and_no_pass_is_null(capsys):
    """A tolerance no run reaches in a 1 s budget: status 1, strict JSON on stdout alone,
    ``answer`` null and the limit stated."""
    code, out = run("tune", MODEL, "--tolerance", "1e-12", "--budget", "1", "--workers",
                    "1", "--json")
    assert code == 1
    doc = json.loads(out)
    assert doc["answer"] is None and doc["passed"] is False
    assert doc["limit"].startswith("best reached ")
    assert all(c["error"] is None or c["error"] > 1e-12 for c in doc["candidates"])


def test_an_answer_off_the_front_says_why():
    """The answer may sit off the Pareto front (a cheaper passing run within the cost
    tie, more knobs moved): the text says so instead of showing a front that seems to
    contradict the answer line; an answer on the front adds nothing."""
    from types import SimpleNamespace as NS

    from reports.tune.output import _answer_off_front
    cheap, answer = NS(passed=True, c=1.91e-3), NS(passed=True, c=1.94e-3)
    res = NS(answer=answer, front=[NS(passed=False, c=1.0e-3), cheap],
             cost=lambda p: p.c)
    (line,) = _answer_off_front(res)
    assert "1.94 ms" in line and "1.91 ms" in line and "15%" in line
    assert _answer_off_front(NS(answer=cheap, front=[cheap], cost=lambda p: p.c)) == []
