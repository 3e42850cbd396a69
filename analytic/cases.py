"""The built-in cases, each shipped as a TOML file in ``analytic/cases/``."""

from __future__ import annotations

from pathlib import Path

from .errors import DescriptionError
from .mechanism import Mechanism
from .toml_io import load_mechanism

CASES_DIR = Path(__file__).parent / "cases"


def case_names() -> list[str]:
    """Names of the built-in cases, sorted."""
    return sorted(p.stem for p in CASES_DIR.glob("*.toml"))


#: Free-motion cases (the IFToMM benchmark problems): loaded by name like the others,
#: not listed by :func:`case_names` (the prescribed-motion runs iterate over those).
FREE_CASES_DIR = CASES_DIR / "free"


def free_case_names() -> list[str]:
    """Names of the built-in free-motion cases, sorted."""
    return sorted(p.stem for p in FREE_CASES_DIR.glob("*.toml"))


def case_path(name: str) -> Path:
    p = CASES_DIR / f"{name}.toml"
    if not p.is_file():
        p = FREE_CASES_DIR / f"{name}.toml"
    if not p.is_file():
        raise DescriptionError(f"no built-in case {name!r}; cases are {case_names()}, "
                               f"free-motion cases {free_case_names()}")
    return p


def load_case(name_or_path: str | Path) -> Mechanism:
    """A built-in case by name, or a mechanism TOML file by path."""
    s = str(name_or_path)
    if s.endswith(".toml") or Path(s).is_file():
        return load_mechanism(s)
    return load_mechanism(case_path(s))
