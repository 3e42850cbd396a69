"""The case catalogue: every case the project ships, each a TOML file under
``analytic/cases/``, found by name.

* the **built-in cases** (``analytic/cases/*.toml``): the worked examples of the notes and
  textbooks, which the report, the model files and the baselines cover
  (:func:`case_names`);
* the **hard cases** (``analytic/cases/hard/*.toml``): linkages made to test numerical
  stability (a crank a hair from its toggle, a parallelogram through its change points),
  which the report's studies run (:func:`hard_case_names`);
* the **free-motion cases** (``analytic/cases/free/*.toml``): the IFToMM benchmark
  problems, released linkages for ``xval simulate`` (:func:`free_case_names`).

:func:`load_case` and :func:`case_path` resolve a name of either kind, so every command
accepts every name the report prints.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from .errors import DescriptionError
from .mechanism import Mechanism
from .toml_io import load_mechanism

CASES_DIR = Path(__file__).parent / "cases"
HARD_CASES_DIR = CASES_DIR / "hard"
#: Free-motion cases: loaded by name like the others, not listed by :func:`case_names`
#: (the prescribed-motion runs iterate over those).
FREE_CASES_DIR = CASES_DIR / "free"


def case_names() -> list[str]:
    """Names of the built-in cases, sorted."""
    return sorted(p.stem for p in CASES_DIR.glob("*.toml"))


def hard_case_names() -> list[str]:
    """Names of the hard cases (numerical stability), sorted."""
    return sorted(p.stem for p in HARD_CASES_DIR.glob("*.toml"))


def free_case_names() -> list[str]:
    """Names of the free-motion cases (IFToMM benchmark problems), sorted."""
    return sorted(p.stem for p in FREE_CASES_DIR.glob("*.toml"))


def case_path(name: str) -> Path:
    """The file of a built-in or hard case ``name``."""
    for folder in (CASES_DIR, HARD_CASES_DIR, FREE_CASES_DIR):
        p = folder / f"{name}.toml"
        if p.is_file():
            return p
    raise DescriptionError(f"no built-in case {name!r}; cases are {case_names()}, "
                           f"hard cases {hard_case_names()}, free-motion cases "
                           f"{free_case_names()}")


def load_case(name_or_path: str | Path) -> Mechanism:
    """A built-in or hard case by name, or a mechanism TOML file by path."""
    s = str(name_or_path)
    if s.endswith(".toml") or Path(s).is_file():
        return load_mechanism(s)
    return load_mechanism(case_path(s))


def case_description(name: str) -> str:
    """The ``description`` of case ``name`` as its file writes it (what
    :func:`load_case` puts in ``Mechanism.description``), read without building the
    mechanism: TOML's top-level keys come before its first table, so only that head is
    parsed (the whole file if the head does not parse alone, e.g. a multi-line string
    with a line starting with ``[``)."""
    text = case_path(name).read_text(encoding="utf-8")
    cut = next((i for i, line in enumerate(text.splitlines(keepends=True))
                if line.lstrip().startswith("[")), None)
    head = "".join(text.splitlines(keepends=True)[:cut]) if cut is not None else text
    try:
        doc = tomllib.loads(head)
    except tomllib.TOMLDecodeError:
        doc = tomllib.loads(text)
    return str(doc.get("description", ""))
