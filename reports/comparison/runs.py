"""Verdict runs: one engine on one compiled linkage, compared with its analytic solution.

:func:`run_verdict` is the one compile -> run -> compare of the project: ``xval compare``
(:mod:`reports.cli.compare`), the report's engine tasks (:mod:`reports.report.build`, through
:func:`run_comparison`), ``xval plot --engine``, the baselines
(:func:`reports.regression.baseline_record.run_and_compare`) and the pytest plugin
(:mod:`reports.regression.pytest_plugin`) all run through it.  Engines are chosen by name from
:mod:`sim_models.engines.registry` and their settings built there (``--set KEY=VALUE``); the
compiled linkage (:func:`sim_models.compile_linkage`) is built once and passed down to
the engine run, comes back up in it (``run.linkage is tree.linkage``), the comparison
reads its reference there, and the tree comes back in the :class:`Verdict`.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

from analytic import LinkageError, Mechanism
from analytic.sweep import input_values
from reports.comparison import quantities
from reports.comparison.compare import Comparison, compare_run, near_event, verdict
from sim_models import SimTree, compile_linkage
from sim_models.engines.registry import available_engines, get_engine, settings_from_options
from sim_models.engines.settings import EngineRefusal
from sim_models.runs.driven import has_instantaneous, instantaneous, not_run, run
from sim_models.runs.engine_run import EngineRun, RunRequest


@dataclass(frozen=True)
class Verdict:
    """One engine's run on one compiled linkage and its comparison with the analytic
    solution.

    ``tree`` is the compiled linkage the run was made from (``tree.linkage`` the
    reference), ``comparisons`` every compared quantity, the engines' own readings
    included (:mod:`reports.comparison.quantities`; :meth:`judged` leaves them out).
    """

    tree: SimTree
    run: EngineRun
    comparisons: tuple[Comparison, ...]

    @property
    def ok(self) -> bool:
        """The verdict: the run finished and every judged quantity is within tolerance."""
        return self.run.ok and verdict(self.comparisons)

    @cached_property
    def near_event(self) -> str | None:
        """For a failed verdict, the limit/singular position or change point the worst
        error sits near (:func:`reports.comparison.compare.near_event`, a 720-point sweep,
        made once); None for a pass or when none is near."""
        return None if self.ok else near_event(list(self.comparisons), self.tree.linkage)

    def judged(self) -> list[Comparison]:
        """The comparisons the verdict judges."""
        return quantities.judged(self.comparisons)


def request_of(values: Mapping[str, object]) -> RunRequest:
    """A :class:`RunRequest` from a mapping of its fields (a baseline record's
    ``request``, a function's keyword arguments); a field not given, or None, takes the
    request's default (the one holder of the run defaults)."""
    names = {f.name for f in dataclasses.fields(RunRequest)}
    return RunRequest(**{k: v for k, v in values.items() if k in names and v is not None})


def run_verdict(linkage: Mechanism | SimTree, engine: str, settings=None,
                request: RunRequest | None = None) -> Verdict:
    """Compile ``linkage`` (unless already a :class:`SimTree`; with ``request.chords``),
    run ``engine`` on it as ``request`` asks (default :class:`RunRequest`'s defaults) and
    compare with the analytic solution.

    ``request.mode == "instantaneous"``: the engine's forward dynamics at the analytic
    state of the sweep's ``request.samples`` inputs (engines without one refuse).
    ``settings``: the engine's settings object (None: its recommended settings)."""
    req = request or RunRequest()
    tree = linkage if isinstance(linkage, SimTree) else \
        compile_linkage(linkage, chords=req.chords)
    if req.mode == "instantaneous":
        r = instantaneous(tree, engine, settings, input_values(tree.linkage, req.samples)[0])
    else:
        r = run(tree, engine, settings, revolutions=req.revolutions, samples=req.samples,
                max_violation=req.max_violation, max_speed_error=req.max_speed_error,
                wall_limit=req.wall_limit)
    return Verdict(tree, r, tuple(compare_run(r)))  # against r.linkage, tree.linkage itself


def crash_text(e: BaseException) -> str:
    """One line naming an exception: its type and the first line of its message."""
    msg = str(e).strip().splitlines()
    return f"{type(e).__name__}: {msg[0]}" if msg else type(e).__name__


def run_verdicts(tree: SimTree, engines: Sequence[str], settings: Mapping[str, object],
                 request: RunRequest, progress=None) -> list[Verdict]:
    """:func:`run_verdict` of each engine in turn (``xval compare``, ``--engine all``).

    One engine's crash never ends the others: an engine that raises anything but a
    refusal of the input is a failed verdict whose run says ``engine crashed: TYPE:
    message`` (every sample "not measured").  Of several engines, one that refuses
    (:class:`EngineRefusal`: it cannot build or run this model) is a failed verdict
    saying so; a refusal by the only engine, or by every engine (the input's fault),
    stays the one-line error of status 2.  ``progress(engine)``: a context manager
    around each run (the terminal's progress line), or None."""
    out: list[Verdict] = []
    refusals: list[EngineRefusal] = []
    for eng in engines:
        with progress(eng) if progress else contextlib.nullcontext():
            try:
                out.append(run_verdict(tree, eng, settings.get(eng), request))
                continue
            except EngineRefusal as e:
                if len(engines) == 1:
                    raise
                refusals.append(e)
                why = f"refused: {crash_text(e).split(': ', 1)[-1]}"
            except LinkageError:
                raise  # bad input: one line, status 2
            except Exception as e:  # noqa: BLE001 - an engine's crash is its failed verdict
                why = f"engine crashed: {crash_text(e)}"
        r = not_run(tree, eng, settings.get(eng), why, request.revolutions, request.samples)
        out.append(Verdict(tree, r, tuple(compare_run(r))))
    if refusals and len(refusals) == len(engines):
        raise refusals[0]
    return out


def engine_list(choice: str, mode: str = "run") -> list[str]:
    """``"all"`` -> every registered engine whose module is present (in the instantaneous
    mode, those with a forward-dynamics call); else the one named."""
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
    refused (:func:`sim_models.engines.registry.settings_from_options`)."""
    return settings_from_options(engines, pairs, options)


def run_comparison(tree, engine: str, settings=None, mode: str = RunRequest.mode,
                   revolutions: int = RunRequest.revolutions,
                   samples: int = RunRequest.samples, wall_limit: float | None = None):
    """:func:`run_verdict` on the compiled linkage ``tree`` as ``(run, comparisons)``
    (the report's engine tasks and ``xval plot --engine``; ``wall_limit``: s of
    stepping, None: none)."""
    v = run_verdict(tree, engine, settings, RunRequest(revolutions, samples, mode=mode,
                                                       wall_limit=wall_limit))
    return v.run, list(v.comparisons)


__all__ = ["Verdict", "crash_text", "engine_list", "request_of", "run_comparison",
           "run_verdict", "run_verdicts", "settings_for"]
