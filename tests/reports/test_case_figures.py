"""A case plot can never disagree with its verdict.

For every built-in case and every registered engine, the figures' own plotted arrays
(:class:`reports.figures.case_figures.CurveFigure`: the analytic line and the engine markers)
are read back: at each judged marker, the distance to the analytic line at the same
input, divided by the quantity's peak over the plotted samples, must not exceed that
quantity's verdict error (:func:`reports.comparison.compare.compare_run`) plus round-off; for a
quantity the verdict does not judge (angles, omegas) the line must be the verdict's own
reference at every sample and the marker the engine's own value.
The error panels' largest value per family must equal the verdict's.  A figure drawn
against the description's nominal-speed sweep (what ``case_figures`` drew before issue
10) must fail the same check wherever the input speed is not constant.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from analytic import case_names, load_case
from reports.comparison.compare import compare_run
from reports.comparison.reference import family_of
from reports.figures.case_figures import curve_figures, error_figure
from sim_models import compile_linkage
from sim_models.engines.registry import available_engines
from sim_models.runs.driven import run

#: Round-off allowed on top of the verdict error: relative (the same numbers reach the
#: plot through a second, vectorised evaluation of the same analytic solution) and
#: absolute in units of the peak (the reference's own last digits).
ROUND_OFF_REL = 1e-6
ROUND_OFF_ABS = 1e-10
#: A quantity identically zero over the cycle (a constant-speed crank's alpha, a piston's
#: angle) is measured on the figure's largest peak, as the verdict does.
ZERO_PEAK = 1e-9

ENGINES = tuple(available_engines())
_RUNS: dict = {}


def runs_of(case: str):
    """Every engine's verdict run of ``case`` and its comparisons (cached per module)."""
    if case not in _RUNS:
        tree = compile_linkage(load_case(case))
        runs = {e: run(tree, e, None, revolutions=2, samples=36) for e in ENGINES}
        comps = {e: compare_run(r) for e, r in runs.items()}
        _RUNS[case] = (tree, runs, comps)
    return _RUNS[case]


def drawn_points(fig, curve) -> np.ndarray:
    """Indices of the line points a reader sees: those of stretches (split at the
    figure's ``breaks``) that span some of the axis; a stretch of one input (a point,
    or a zero-length segment) draws nothing, so a marker on it is off every curve."""
    idx = np.split(np.arange(len(curve.x)), list(fig.breaks))
    keep = [i for i in idx if len(i) >= 2 and np.ptp(np.asarray(curve.x)[i]) > 0]
    return np.concatenate(keep) if keep else np.zeros(0, int)


def plotted_excess(fig, comps: dict, refs: dict | None = None) -> list[str]:
    """Markers farther from the plotted analytic line than the verdict allows.

    A judged curve (alpha, s'', effort, |F|): the largest distance of a judged marker
    from the line at its input, over the curve's peak there, within the quantity's
    verdict error.  A curve the verdict does not judge (angle, omega): the line at each
    marker is the verdict's reference there (``refs[engine]``:
    :func:`reports.comparison.reference.reference_of`), to round-off, and the marker is the
    engine's own value (angles: the same difference modulo a turn)."""
    by_q = {e: {c.quantity: c for c in cs} for e, cs in comps.items()}
    out = []
    dist, peaks, lines = {}, {}, {}
    for c in fig.curves:
        for e, (x, y, judged) in c.markers.items():
            if e not in comps:
                continue
            x, y = np.asarray(x, float), np.asarray(y, float)
            ok = judged & np.isfinite(y)
            drawn = drawn_points(fig, c)
            span = max(np.ptp(c.x), 1.0)
            k = np.array([drawn[int(np.argmin(np.abs(c.x[drawn] - xv)))] for xv in x[ok]],
                         int)
            far = np.abs(c.x[k] - x[ok]) > 1e-9 * span
            assert not far.any(), \
                (f"{fig.title}: {c.label} {e}: markers at {x[ok][far][:3]} have no drawn "
                 f"line point at their input (nearest drawn {c.x[k][far][:3]})")
            ya = np.asarray(c.y, float)[k]
            dist[c.label, e] = float(np.max(np.abs(y[ok] - ya))) if ok.any() else 0.0
            peaks[c.label, e] = float(np.max(np.abs(ya))) if ok.any() else 0.0
            lines[c.label, e] = (ok, ya, y[ok])
    for c in fig.curves:
        for e in [e for e in c.markers if e in comps]:
            top = max(v for (lab, ee), v in peaks.items() if ee == e)
            pk = peaks[c.label, e]
            pk = top if pk <= ZERO_PEAK * top else pk
            if c.quantity:
                rel = dist[c.label, e] / pk if pk > 0 else 0.0
                bound = by_q[e][c.quantity].normalised
                if not rel <= bound * (1 + ROUND_OFF_REL) + ROUND_OFF_ABS:
                    out.append(f"{fig.title}: {c.label} ({e}) plotted {rel:.3g} of peak, "
                               f"verdict {bound:.3g}")
                continue
            if refs is None or fig.name not in ("angle", "omega"):
                continue
            ref, run_ = refs[e]
            b = list(run_.body_names).index(c.label)
            ok, ya, ye = lines[c.label, e]
            if fig.name == "angle":
                want_line = np.degrees(ref.kin.theta[ok, b])
                want_gap = np.degrees(run_.theta[ok, b]) - want_line
                off = np.mod(ya - want_line + 180.0, 360.0) - 180.0
                gap = np.mod(ye - ya - want_gap + 180.0, 360.0) - 180.0
                scale = 360.0
            else:
                off, gap = ya - ref.kin.omega[ok, b], ye - run_.omega[ok, b]
                scale = pk
            worst = float(np.max(np.abs(np.r_[off, gap]))) / scale if ok.any() else 0.0
            if not worst <= ROUND_OFF_ABS:
                out.append(f"{fig.title}: {c.label} ({e}) plotted {worst:.3g} of peak off "
                           "the verdict's reference or the engine's value")
    return out


def refs_of(tree, runs):
    from reports.comparison.reference import reference_of
    return {e: (reference_of(r), r) for e, r in runs.items()}


@pytest.mark.parametrize("case", case_names())
def test_plots_agree_with_verdict(case):
    tree, runs, comps = runs_of(case)
    figs = curve_figures(case, runs, tree.linkage, extra=("slider_s",), tree=tree)
    assert {f.name for f in figs} >= {"angle", "omega", "alpha"}
    for f in figs:  # the engines' slider positions are drawn where the run has them
        if f.name == "slider_s":
            assert all(set(c.markers) == set(runs) for c in f.curves), f.title
    bad = [m for f in figs for m in plotted_excess(f, comps, refs_of(tree, runs))]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("case", case_names())
def test_error_panels_are_the_verdict(case):
    """Every judged family is drawn, and its largest plotted error is the verdict's."""
    tree, runs, comps = runs_of(case)
    ef = error_figure(case, runs, comps, tree.linkage, 1e-3)
    for e, cs in comps.items():
        judged = [c for c in cs if not c.quantity.endswith("[engine]")]
        panel = ef.panels[e]
        for fam in {family_of(c.quantity) for c in judged}:
            want = max(c.normalised for c in judged if family_of(c.quantity) == fam)
            got = float(np.nanmax(panel["families"][fam]))
            assert math.isclose(got, want, rel_tol=1e-9, abs_tol=1e-15), (e, fam, got, want)
        w = max(judged, key=lambda c: c.normalised)
        assert panel["worst"][0] == w.quantity


def nominal_line(runs, linkage):
    """The reference case_figures drew before: the description's nominal driver speed
    at every input (``lk.sweep(360)``), here at the plotted inputs."""
    from reports.comparison.reference import analytic_line
    u, kin, _ = analytic_line(runs, linkage)
    nominal = linkage.kinematics(kin.value, on_singular="flag")
    frc = linkage.forces(nominal) if linkage.mech.has_mass else None
    return u, nominal, frc


@pytest.mark.parametrize("case", [c for c in case_names()
                                  if load_case(c).driver.acceleration != 0.0])
def test_nominal_speed_reference_is_caught(case):
    """Where the input accelerates, lines at the nominal speed fail the check for every
    engine (the defect of issue 10: hibbeler-16-121's crank omega line at 3 rad/s,
    markers at 6 to 7.5)."""
    tree, runs, comps = runs_of(case)
    figs = curve_figures(case, runs, tree.linkage, line=nominal_line)
    for e in runs:
        bad = [m for f in figs for m in plotted_excess(f, {e: comps[e]}, refs_of(tree, runs))]
        assert bad, f"{case} / {e}: the nominal-speed figure passed the check"
