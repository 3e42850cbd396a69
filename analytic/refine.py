"""Events located on the solver, not between the sweep's samples.

A sweep samples the input; an event (a rocker's extreme angle, a slider's dead centre,
a dyad's least transmission angle) lies between two samples.  Interpolating the
samples places it to the grid's accuracy only (O(h^2): 7e-4 deg at 1 deg spacing).
Here each one is bracketed by the samples and then located by a safeguarded Newton
iteration on the exact solver (:meth:`analytic.kinematics.Linkage.kinematics` at unit
input velocity and zero input acceleration, where a body's angular velocity is
``d theta / d input`` and its angular acceleration ``d^2 theta / d input^2``: the
function and its exact derivative), all brackets of a kind at once, to
:data:`INPUT_TOL`.  The located input is then as exact as the solver; what a sweep
prints there (6 decimals) is within the tolerance of the digits shown.

Inputs are SI (rad or m) throughout.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .positions import size_of

#: A located event's input tolerance: 1e-12 rad (5.7e-11 deg), or 1e-12 of the
#: mechanism's size (m) for a prismatic input: below the 1e-9 deg (or m) the sweep's
#: six printed decimals need, and above the ~1e-15 relative that the rounding of the
#: rates leaves in the root of a simple zero.
INPUT_TOL = 1e-12
#: Newton steps at most (quadratic convergence from a bracket of one grid step needs
#: 4-6; a step that leaves the bracket is replaced by bisection, 1 bit a step).
MAX_STEPS = 100

#: ``rate(kin) -> (g, dg)``: a quantity that changes sign at the event, and its
#: derivative with respect to the input (NaN where there is none: the iteration is then
#: regula falsi), per configuration (``(N,)`` each), from a
#: :class:`analytic.kinematics.Kinematics` at unit input velocity and zero input
#: acceleration.
Rate = Callable[[object], tuple[np.ndarray, np.ndarray]]


def tolerance(linkage) -> float:
    """:data:`INPUT_TOL` in the input's units (rad, or m scaled by the mechanism's size)."""
    return INPUT_TOL * (1.0 if linkage.driver_is_revolute else size_of(linkage.topo))


def unit_rate_kinematics(linkage, x: np.ndarray):
    """Kinematics at inputs ``x`` (SI) at unit input velocity and zero acceleration: the
    rates are derivatives with respect to the input."""
    x = np.asarray(x, float)
    return linkage.kinematics(x, np.ones(len(x)), np.zeros(len(x)), on_singular="flag")


def sign_brackets(x: np.ndarray, y: np.ndarray, periodic: bool, scale: float = 0.0
                  ) -> list[tuple[int, int]]:
    """Pairs of sample indices ``(i, k)`` between which ``y`` changes sign.

    Samples within 1e-9 of the series' peak (or of ``scale``, the size the series would
    have if it moved at all, when larger) of zero are round-off, not sign: a stretch of
    them (a parallelogram's translating coupler) yields at most one bracket, between
    the significant samples on either side, and a series of round-off alone none.  With
    ``periodic``, the last sample pairs with the first (``k < i``)."""
    n = len(y)
    y = np.asarray(y, float)
    peak = max(float(np.max(np.abs(y))) if n else 0.0, scale)
    sig = np.flatnonzero(np.abs(y) > 1e-9 * peak) if peak > 0 else np.array([], int)
    if len(sig) < 2:
        return []
    a, b = sig[:-1], sig[1:]
    if periodic:
        a, b = np.append(a, sig[-1]), np.append(b, sig[0])
    # only the pairs whose signs differ (a list of every pair held ~120 B a sample)
    flip = np.flatnonzero(y[a] * y[b] < 0)
    return [(int(i), int(k)) for i, k in zip(a[flip], b[flip], strict=True)]


def locate(linkage, lo: np.ndarray, hi: np.ndarray, rate: Rate, zero=None) -> np.ndarray:
    """The input in each bracket ``[lo_i, hi_i]`` (SI, ``lo < hi``) where ``rate``
    changes sign, to :func:`tolerance`; NaN where the rate is not finite at an end or
    has the same sign at both (no sign change to locate).  ``zero`` (per bracket,
    default 0): magnitudes at most this are round-off of 0; where the rate is 0 over an
    interval, its middle is the input returned."""
    a, b = np.asarray(lo, float).copy(), np.asarray(hi, float).copy()
    m = len(a)
    if not m:
        return np.zeros(0)
    zero = np.zeros(m) if zero is None else np.asarray(zero, float)

    def rate_(kn, ids):  # the rate with its round-off set to 0
        g, dg = _call(rate, kn, ids)
        return np.where(np.abs(g) <= zero[ids], 0.0, g), dg
    rate_.per_bracket = True
    g, _ = _call(rate_, unit_rate_kinematics(linkage, np.concatenate([a, b])),
                 np.concatenate([np.arange(m), np.arange(m)]))
    ga, gb = g[:m].copy(), g[m:].copy()
    out = np.full(m, np.nan)
    ok = np.isfinite(ga) & np.isfinite(gb) & (ga * gb <= 0)
    out[ok & (ga == 0)] = a[ok & (ga == 0)]
    out[ok & (gb == 0) & (ga != 0)] = b[ok & (gb == 0) & (ga != 0)]
    act = np.flatnonzero(ok & (ga != 0) & (gb != 0))
    if not act.size:
        return out
    tol = tolerance(linkage)
    a, b, ga, gb, ids = a[act], b[act], ga[act], gb[act], act
    x = a - ga * (b - a) / (gb - ga)  # the interpolated crossing: the first guess
    failed = np.zeros(len(x), bool)
    kept = np.zeros(len(x), int)  # which end the last two steps kept (Illinois)
    for _ in range(MAX_STEPS):
        g, dg = _call(rate_, unit_rate_kinematics(linkage, x), ids)
        failed |= ~np.isfinite(g)  # a singular configuration inside: not located
        left = np.sign(g) == np.sign(ga)  # a 0 (or NaN) moves neither end
        right = np.sign(g) == np.sign(gb)
        a, ga = np.where(left, x, a), np.where(left, g, ga)
        b, gb = np.where(right, x, b), np.where(right, g, gb)
        # without a derivative (dg NaN): regula falsi, the end kept twice in a row
        # halved (Illinois: superlinear, never stalls on one side)
        side = np.where(left, 1, -1)
        gb = np.where(side + kept == 2, 0.5 * gb, gb)
        ga = np.where(side + kept == -2, 0.5 * ga, ga)
        kept = side
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = np.where(np.isfinite(dg), x - g / dg, (a * gb - b * ga) / (gb - ga))
        inside = np.isfinite(newton) & (newton >= a) & (newton <= b)
        nxt = np.where(inside, newton, 0.5 * (a + b))
        done = (g == 0) | ~np.isfinite(g) | (np.abs(nxt - x) <= tol) | (b - a <= tol)
        x = np.where((g == 0) | ~np.isfinite(g), x, nxt)
        if done.all():
            break
    flat = (g == 0) & ~failed
    if flat.any():  # a zero over a band (a dyad snapped to its toggle): its middle
        x[flat] = _zero_band_middle(linkage, rate_, ids[flat], a[flat], x[flat], b[flat], tol)
    out[act] = np.where(failed, np.nan, x)
    return out


def _zero_band_middle(linkage, rate, ids, a, z, b, tol):
    """The middle of the interval around ``z`` where ``rate`` is exactly 0 (``a`` and
    ``b``: the nearest inputs either side where it is not): both edges by bisection.
    The solver sets a dyad within :data:`analytic.tolerances.TOGGLE_SNAP` of its
    toggle exactly onto it, so a determinant is exactly 0 over a band about 1e-6 wide,
    centred on the singular position to first order."""
    lo = np.stack([a, z])  # (2, k): bracket of the left edge, then the right's
    hi = np.stack([z, b])
    for _ in range(MAX_STEPS):
        m = 0.5 * (lo + hi)
        g, _ = _call(rate, unit_rate_kinematics(linkage, m.ravel()), np.tile(ids, 2))
        inner = (g.reshape(m.shape) == 0)  # inside the band
        # left edge: band on the right (hi side); right edge: band on the left (lo side)
        lo[0], hi[0] = np.where(inner[0], lo[0], m[0]), np.where(inner[0], m[0], hi[0])
        lo[1], hi[1] = np.where(inner[1], m[1], lo[1]), np.where(inner[1], hi[1], m[1])
        if np.all(hi - lo <= tol):
            break
    return 0.5 * (0.5 * (lo[0] + hi[0]) + 0.5 * (lo[1] + hi[1]))


def _call(rate, kin, ids):
    """``rate(kin)``, or ``rate(kin, ids)`` for a rate that serves several brackets
    (``ids``: the bracket of each configuration)."""
    g, dg = rate(kin, ids) if getattr(rate, "per_bracket", False) else rate(kin)
    return np.asarray(g, float), np.asarray(dg, float)


def sign_changes(linkage, x: np.ndarray, y: np.ndarray, periodic: bool, rate: Rate,
                 scale: float = 0.0) -> list[float]:
    """Inputs (SI) where the sampled series ``y(x)`` changes sign, located on the solver
    (``rate``: the same quantity and its derivative or NaN); see
    :func:`_roots_together`."""
    y = np.asarray(y, float)
    zero = 1e-9 * max(float(np.max(np.abs(y))) if len(y) else 0.0, scale)  # as the samples'
    return _roots_together(linkage, np.asarray(x, float), periodic,
                           {0: (y, scale, rate)}, zero)[0] if len(x) > 1 else []


def rate_series(linkage, kin, regular) -> dict:
    """The series whose sign changes are the limit positions of :func:`turning_points`:
    key (``("group", g)`` or ``("slider", joint)``) -> (sampled rate on the ``regular``
    samples times the input's sign; its scale; the rate as a function of a
    :class:`analytic.Kinematics` for the root finder).  One piece for the in-memory
    sweep and the streamed one (:mod:`analytic.sweep_facts`, block by block)."""
    topo = linkage.topo
    sign = np.sign(kin.velocity)[regular]
    w_in = float(np.max(np.abs(kin.velocity))) if len(regular) else 0.0
    size = size_of(topo)
    rev = linkage.driver_is_revolute
    series = {}  # key -> (sampled series, scale, rate)
    for g in range(topo.n_groups):
        b = int(np.flatnonzero(topo.group_of == g)[0])
        series[("group", g)] = (kin.omega[:, b][regular] * sign,
                                w_in * (1.0 if rev else 1 / size),
                                lambda k, b=b: (k.omega[:, b], k.alpha[:, b]))
    for j in topo.prismatic:
        if j == topo.driver_joint:
            continue
        jn = topo.joint_names[j]
        series[("slider", jn)] = (kin.slider(jn)[1][regular] * sign,
                                  w_in * (size if rev else 1.0),
                                  lambda k, jn=jn: k.slider(jn)[1:])
    return series


def turning_points(linkage, kin, periodic: bool) -> dict:
    """The limit positions of every rotation group and every slider over a sweep, all
    located in one iteration: ``{("group", g): [input SI, ...], ("slider", joint):
    [...]}``.  A group's are where its angular velocity changes sign, a slider's where
    its sliding velocity does (:func:`sign_brackets` of the regular samples,
    samples below 1e-9 of the input's rate scale being round-off).  Computed once per
    sweep (kept on ``kin``): the events and the summary read the same inputs."""
    memo = getattr(kin, "memo", None)
    got = None if memo is None else memo.get("turning_points")
    if got is not None and got[0] == periodic:
        return got[1]
    from .tolerances import SINGULAR_CONDITION
    x = np.asarray(kin.value, float)
    regular = np.asarray(kin.condition < SINGULAR_CONDITION)
    xr = x[regular]
    series = rate_series(linkage, kin, regular)
    out = _roots_together(linkage, xr, periodic, series) if len(xr) > 1 else \
        {k: [] for k in series}
    if memo is not None:
        memo["turning_points"] = (periodic, out)
    return out


def _roots_together(linkage, x, periodic, series, zero: float = 0.0) -> dict:
    """The sign changes of several sampled series over the same inputs ``x``
    (:func:`sign_brackets`), located together by :func:`locate_brackets`."""
    period = (x[-1] - x[0]) + (x[1] - x[0]) if periodic else 0.0
    brackets = {}
    for key, (y, scale, _) in series.items():
        y = np.asarray(y, float)
        brackets[key] = [(x[i], x[k] if k > i else x[k] + period, y[i], y[k])
                         for i, k in sign_brackets(x, y, periodic, scale)]
    return locate_brackets(linkage, brackets, {k: r for k, (_, _, r) in series.items()},
                           float(x[0]), period, zero)


def locate_brackets(linkage, brackets: dict, rates: dict, x0: float, period: float,
                    zero: float = 0.0) -> dict:
    """The roots in the brackets ``{key: [(x_i, x_k, y_i, y_k), ...]}`` (the sampled
    series ``y`` changes sign from ``x_i`` to ``x_k``; ``x_k`` one ``period`` on for
    the pair that closes a periodic sweep), each of its series' ``rates[key]``, located
    together by one :func:`locate` (one solve a step for all); a bracket the solver
    cannot resolve keeps the interpolated crossing, and a periodic sweep's roots
    (``period > 0``) are wrapped into its turn ``[x0, x0 + period)``.  A streamed
    sweep finds its brackets block by block (:mod:`analytic.sweep_facts`)."""
    keys, lo, hi, guess = [], [], [], []
    for key, found in brackets.items():
        for xi, x1, yi, yk in found:
            keys.append(key)
            lo.append(min(xi, x1))  # inputs given in decreasing order too
            hi.append(max(xi, x1))
            guess.append(xi + (x1 - xi) * yi / (yi - yk))
    out = {k: [] for k in brackets}
    if not keys:
        return out
    order = list(brackets)
    idx = np.array([order.index(k) for k in keys])
    rate_of = [rates[k] for k in order]

    def rate(kn, ids):  # each bracket's own series, from one solve of all of them
        sel = idx[ids]
        g, dg = np.empty(kn.n), np.empty(kn.n)
        for r in np.unique(sel):
            gi, di = rate_of[r](kn)
            g[sel == r], dg[sel == r] = np.asarray(gi)[sel == r], np.asarray(di)[sel == r]
        return g, dg
    rate.per_bracket = True
    got = locate(linkage, np.array(lo), np.array(hi), rate, np.full(len(lo), zero))
    v = np.where(np.isfinite(got), got, np.array(guess))
    if period:
        v = x0 + np.mod(v - x0, period)
    for key, u in zip(keys, v, strict=True):
        out[key].append(float(u))
    return out


# --------------------------------------------------------------------------- transmission
def _rotating_body(linkage, vectors: np.ndarray, E: np.ndarray) -> int:
    """The body whose orientation a link vector of a dyad turns with: the one whose
    angle to it stays constant over the configurations (``vectors`` ``(N,)``, ``E``
    ``(N, B)`` complex)."""
    rel = np.angle(vectors[:, None] * E.conj())
    spread = np.abs(np.angle(np.exp(1j * (rel - rel[:1]))))
    return int(np.argmin(np.max(spread, axis=0)))


def least_transmission(linkage, kin, periodic: bool) -> list[tuple[str, float, float, float]]:
    """Each dyad's least transmission angle (folded into 0..90 deg) over a sweep:
    ``(joint, least_deg, at (SI), raw_deg)``.  An interior least value is located on
    the solver where the two links' relative angular velocity vanishes (the transmission
    angle is the angle between them); one at an end of a limited sweep stays there."""
    memo = getattr(kin, "memo", None)
    got = None if memo is None else memo.get("least_transmission")
    if got is not None and got[0] == periodic:
        return got[1]
    out = _least_transmission(linkage, kin, periodic)
    if memo is not None:  # the events and the summary read it
        memo["least_transmission"] = (periodic, out)
    return out


def _least_transmission(linkage, kin, periodic: bool) -> list:
    x = np.asarray(kin.value, float)
    n = len(x)
    tr = kin.transmission
    if not tr or not n:
        return []
    least = []
    for jn, mu in tr.items():
        mu = np.asarray(mu, float)
        i = int(np.argmin(np.minimum(mu, 180.0 - mu)))
        least.append((jn, i, float(mu[i])))
    return locate_least_transmission(linkage, least, n, lambda idx: x[np.asarray(idx)],
                                     periodic)


def locate_least_transmission(linkage, least: list, n: int, x_at, periodic: bool) -> list:
    """:func:`least_transmission` from each dyad's least sample ``(joint, index, raw
    deg)`` (the first where the folded angle is least) of ``n``; ``x_at(indices)``:
    the sweep's inputs at those indices (SI).  A streamed sweep finds the least samples
    block by block (:mod:`analytic.sweep_facts`)."""
    probe = None
    out = []
    for jn, i, raw in least:
        at, least_ = float(x_at([i])[0]), min(raw, 180.0 - raw)
        if n >= 3 and (periodic or 0 < i < n - 1):
            if probe is None:  # configurations spread over the sweep, to tell the bodies
                probe = unit_rate_kinematics(linkage,
                                             x_at(np.linspace(0, n - 1, 9).astype(int)))
                vecs = {name: (e1, e2) for name, e1, e2 in probe.transmission_vectors}
            e1, e2 = vecs[jn]
            b1, b2 = (_rotating_body(linkage, e, probe.E) for e in (e1, e2))
            xf, x1, xl = (float(v) for v in x_at([0, 1, n - 1]))
            period = (xl - xf) + (x1 - xf) if periodic else 0.0
            lo = float(x_at([i - 1])[0]) if i > 0 else xl - period
            hi = float(x_at([i + 1])[0]) if i < n - 1 else xf + period
            got = locate(linkage, np.array([min(lo, hi)]), np.array([max(lo, hi)]),
                         lambda k, b1=b1, b2=b2: (k.omega[:, b2] - k.omega[:, b1],
                                                  k.alpha[:, b2] - k.alpha[:, b1]))[0]
            if math.isfinite(got):
                m = float(unit_rate_kinematics(linkage, np.array([got])).transmission[jn][0])
                f = min(m, 180.0 - m)
                if f <= least_:  # the located extreme is the least (never above a sample)
                    at, least_, raw = got, f, m
                    if periodic:
                        at = float(xf + np.mod(at - xf, period))
        out.append((jn, least_, at, raw))
    return out


# --------------------------------------------------------------------------- peaks
#: A located peak's input tolerance relative to the bracket's scale (1 rad or the
#: mechanism's size): a maximum's position is determined only to ~sqrt(eps) of its
#: curvature (the value is flat there), so 1e-9 of a radian (6e-8 deg) is what a
#: bracketed minimiser can reach; the peak's value is then exact to rounding.
PEAK_XTOL = 1e-9


#: Configurations per round of :func:`peak`: each round narrows the bracket 64-fold.
PEAK_GRID = 129


def peak(linkage, lo: float, hi: float, value: Callable[[np.ndarray], np.ndarray]
         ) -> tuple[float, float] | None:
    """The input in ``[lo, hi]`` (SI) where ``value(inputs)`` (magnitudes from the solver
    at those inputs, ``(N,)``) is largest, and that value: a grid of :data:`PEAK_GRID`
    configurations around the best so far, narrowed 64-fold a round until the bracket
    is :data:`PEAK_XTOL` (one vectorised solve a round).  ``None`` when the value is not
    finite inside."""
    tol = PEAK_XTOL * (1.0 if linkage.driver_is_revolute else size_of(linkage.topo))
    best = None
    for _ in range(12):
        t = np.linspace(lo, hi, PEAK_GRID)
        v = np.asarray(value(t), float)
        if not np.all(np.isfinite(v)):
            return None
        k = int(np.argmax(v))
        best = (float(t[k]), float(v[k]))
        if abs(hi - lo) <= tol:
            break
        lo, hi = t[max(k - 1, 0)], t[min(k + 1, PEAK_GRID - 1)]
    return best
