"""Verdict runs: one engine on one compiled linkage, compared with its analytic solution.

Used by ``xval compare`` (:mod:`reports.cli_engines`) and the report's engine tasks
(:mod:`reports.report`).  Engines are chosen by name from :mod:`sim_models.registry` and
their settings built there (``--set KEY=VALUE``); the compiled linkage
(:func:`sim_models.compile_linkage`) is built once and passed down to the engine run and
the comparison.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence


def engine_list(choice: str, mode: str = "run") -> list[str]:
    """``"all"`` -> every registered engine whose module is present (in the instantaneous
    mode, those with a forward-dynamics call); else the one named."""
    from sim_models.engines import has_instantaneous
    from sim_models.registry import available_engines, get_engine
    if choice == "all":
        names = list(available_engines())
        return [n for n in names if has_instantaneous(n)] if mode == "instantaneous" \
            else names
    return [get_engine(choice).name]


def settings_for(engines: Sequence[str], pairs: Sequence[str] = (),
                 options: Mapping[str, tuple[str, object]] | None = None) -> dict:
    """Each engine's settings: its recommended defaults, then the option flags
    ``options`` (``{"--timestep": ("timestep", 1e-4)}``, applied where the engine has the
    field), then the ``KEY=VALUE`` / ``ENGINE.KEY=VALUE`` strings of ``--set``; every
    value within the settings' ranges, a flag and a ``--set`` of the same setting
    refused (:func:`sim_models.registry.settings_from_options`)."""
    from sim_models.registry import settings_from_options
    return settings_from_options(engines, pairs, options)


def run_comparison(tree, engine: str, settings=None, mode: str = "run",
                   revolutions: int = 2, samples: int = 36):
    """Run ``engine`` on the compiled linkage ``tree`` and compare: ``(run, comparisons)``.

    ``mode="instantaneous"``: the engine's forward dynamics at the analytic state of the
    sweep's inputs (engines without one refuse)."""
    from analytic.sweep import input_values
    from reports.compare import compare_run
    from sim_models.engines import instantaneous, run
    if mode == "instantaneous":
        vals = input_values(tree.linkage, samples)[0]
        r = instantaneous(tree, engine, settings, vals)
    else:
        r = run(tree, engine, settings, revolutions=revolutions, samples=samples)
    return r, compare_run(r, tree.linkage)
