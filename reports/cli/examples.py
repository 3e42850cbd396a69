"""The examples that end every ``xval`` command's ``--help`` (plain text, one command a
line, each one a real invocation that runs from an empty folder in the order listed;
tests/reports/test_cli_help.py parses every one with the real parser).

A ``#`` starts a comment, as in a shell: it says what a line needs (a file an earlier
example writes, a display)."""

from __future__ import annotations

import argparse

#: ``xval --help``'s examples: the five-minute tour.
TOUR = (
    "xval cases",
    "xval solve seed-four-bar --angle 30",
    "xval compare seed-four-bar --engine mujoco",
    "xval simulate iftomm-a01-pendulum --duration 5 --engine mujoco",
    "xval report --quick",
)

#: Each command's examples (a command with commands of its own, ``baseline``, has a
#: key per command, ``"baseline record"``, and its own key lists them all).
EXAMPLES: dict[str, tuple[str, ...]] = {
    "cases": ("xval cases",),
    "solve": (
        "xval solve seed-four-bar --angle 30",
        "xval solve seed-slider-crank --angle 45 --units mm,deg,rpm",
        "xval solve six-bar --angle 120 --omega 10 --json",
    ),
    "sweep": (
        "xval sweep seed-four-bar --points 360 --csv four-bar.csv",
        "xval sweep offset-slider-crank --range 0 90 --points 91 --csv quarter.csv",
        "xval sweep six-bar --points 100000 --parquet six-bar.parquet",
    ),
    "explain": (
        "xval explain seed-four-bar --angle 30",
        "xval explain seed-slider-crank --angle 45 --format html --out slider.html",
    ),
    "models": (
        "xval models seed-four-bar --out models",
        "xval models --out models     # every built-in case",
    ),
    "compare": (
        "xval compare seed-four-bar --engine mujoco",
        "xval compare seed-slider-crank --engine pybullet --samples 36 --json",
        "xval compare six-bar --engine mujoco --junit six-bar.xml --summary six-bar.md",
    ),
    "baseline record": (
        "xval baseline record seed-four-bar six-bar --engine mujoco --out base.json",
        "xval baseline record iftomm-a01-pendulum --free --engine mujoco --out a01.json",
    ),
    "baseline check": (
        "xval baseline check base.json     # a file xval baseline record wrote",
        "xval baseline check base.json --engine mujoco --junit drift.xml",
    ),
    "report": (
        "xval report --quick",
        "xval report --cases seed-four-bar --out my-report",
    ),
    "tune": (
        "xval tune seed-four-bar --engine mujoco --budget 20 --out mujoco.json",
        "xval tune six-bar --engine exudyn --budget 20 --json",
    ),
    "import": (
        "xval models seed-four-bar --out models     # an MJCF model to read",
        "xval import models/seed-four-bar.xml --out four-bar.toml",
    ),
    "simulate": (
        "xval simulate iftomm-a01-pendulum --duration 10",
        "xval simulate seed-four-bar --duration 2 --csv free.csv",
        "xval simulate iftomm-a03-andrews --engine mujoco --junit andrews.xml",
    ),
    "plot": (
        "xval plot seed-four-bar --out four-bar.png",
        "xval plot seed-slider-crank --engine mujoco --what angle,torque --out sc.svg",
        "xval plot iftomm-a01-pendulum --duration 5 --out pendulum.png",
    ),
    "animate": (
        "xval animate seed-four-bar --out four-bar.gif",
        "xval animate iftomm-a01-pendulum --duration 4 --frames 48 --out pendulum.html",
    ),
    "view": (
        "xval view seed-four-bar     # needs a display",
        "xval view six-bar --seconds 5",
    ),
}
EXAMPLES["baseline"] = EXAMPLES["baseline record"][:1] + EXAMPLES["baseline check"][:1]


def examples_text(lines: tuple[str, ...]) -> str:
    """The ``examples:`` block of a ``--help``: each line indented two spaces."""
    return "examples:\n" + "\n".join(f"  {line}" for line in lines)


def help_kw(command: str, line: str) -> dict:
    """``add_parser`` keywords for ``command`` (a key of :data:`EXAMPLES`): its one plain
    ``line`` as the description, its examples as the epilog, both printed as written."""
    return {"description": line, "epilog": examples_text(EXAMPLES[command]),
            "formatter_class": argparse.RawDescriptionHelpFormatter}
