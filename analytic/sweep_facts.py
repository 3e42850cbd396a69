"""What a sweep's events and summary read of its per-sample series, whole or block by block.

The events (:func:`analytic.sweep.find_events`) and the summary
(:func:`analytic.summary.summarise`) need, of every series of a sweep, only a few
numbers: where it changes sign (brackets of samples, then located on the solver), its
least and greatest samples with their neighbours, its first and last samples, how
often it reverses, maxima.  :class:`ArrayFacts` reads them from the whole arrays of an
in-memory sweep; :class:`StreamFacts` gathers the same numbers block by block as a
streamed sweep (:mod:`analytic.stream`) solves it, carrying across each boundary what
sign-change detection and neighbours need (the last significant sample, the last
sample), and holds nothing per sample: its memory does not grow with the point count.

Sign changes skip samples within 1e-9 of the series' peak of zero
(:func:`analytic.refine.sign_brackets`), and the peak is known only at the end.  A
block is judged against the peak so far (never above the final one); where a sample
kept as significant turns out to be below the final threshold (a series whose first
blocks are all tiny), :meth:`StreamFacts.finish` asks for a second pass with the
final peak known (:attr:`SignTracker.exact`), so the brackets are exactly those of
the whole series.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .refine import (
    least_transmission,
    locate_brackets,
    locate_least_transmission,
    rate_series,
    sign_changes,
    turning_points,
)
from .tolerances import SINGULAR_CONDITION

#: a sample is round-off, not sign, within this fraction of the series' peak of zero
#: (the rule of :func:`analytic.refine.sign_brackets`)
ROUND_OFF = 1e-9


class SignTracker:
    """Sign changes of a series fed block by block (:func:`analytic.refine.sign_brackets`'s
    rule): ``pairs`` ``[(x_i, x_k, y_i, y_k, aux_i, aux_k)]`` between consecutive
    significant samples of opposite signs (the product test), and ``flips``, how many
    consecutive significant samples differ in sign (the sign test of
    :func:`analytic.summary._reversals`).  ``scale``: the size the series would have
    if it moved at all (see ``sign_brackets``)."""

    def __init__(self, scale: float = 0.0, keep: bool = True):
        self.scale, self.keep = float(scale), keep
        self.peak = 0.0
        self.nan = False
        self.minsig = math.inf  # least |y| of a sample counted significant
        self.nsig = 0
        self.first = self.last = None  # (x, y, aux) of the first/last significant sample
        self.pairs: list = []
        self.flips = 0

    def feed(self, x, y: np.ndarray, aux=None) -> None:
        y = np.asarray(y, float)
        if not len(y) or self.nan:
            return
        m = float(np.max(np.abs(y)))
        if math.isnan(m):  # the whole series' peak is NaN: no sign change at all
            self.nan = True
            return
        self.peak = max(self.peak, m)
        ref = max(self.peak, self.scale)
        if not ref > 0:
            return
        sig = np.flatnonzero(np.abs(y) > ROUND_OFF * ref)
        if not len(sig):
            return
        ys = y[sig]
        self.minsig = min(self.minsig, float(np.min(np.abs(ys))))
        xs = None if x is None else np.asarray(x, float)[sig]
        if self.last is not None:  # the pair across the boundary first
            py = self.last[1]
            self.flips += int(np.sign(py) != np.sign(ys[0]))
            if self.keep and py * ys[0] < 0:
                self.pairs.append((self.last[0], float(xs[0]), py, float(ys[0]),
                                   self.last[2], _row(aux, sig[0])))
        self.flips += int(np.count_nonzero(np.sign(ys[:-1]) != np.sign(ys[1:])))
        if self.keep:
            for j in np.flatnonzero(ys[:-1] * ys[1:] < 0):
                self.pairs.append((float(xs[j]), float(xs[j + 1]), float(ys[j]),
                                   float(ys[j + 1]), _row(aux, sig[j]), _row(aux, sig[j + 1])))

        def row(j):
            return (None if xs is None else float(xs[j]), float(ys[j]), _row(aux, sig[j]))
        if self.first is None:
            self.first = row(0)
        self.last = row(len(sig) - 1)
        self.nsig += len(sig)

    @property
    def exact(self) -> bool:
        """Whether every sample counted significant is so against the final peak (else
        feed the series again to a tracker whose ``scale`` is :attr:`final_scale`)."""
        return self.nan or self.nsig == 0 or \
            self.minsig > ROUND_OFF * max(self.peak, self.scale)

    @property
    def final_scale(self) -> float:
        return max(self.peak, self.scale)

    def brackets(self, periodic: bool, period: float) -> list:
        """``[(x_i, x_k, y_i, y_k, aux_i, aux_k)]`` as ``sign_brackets`` pairs them (the
        closing pair of a periodic series last, ``x_k`` one ``period`` on)."""
        if self.nan or self.nsig < 2:
            return []
        out = list(self.pairs)
        if periodic and self.last[1] * self.first[1] < 0:
            out.append((self.last[0], self.first[0] + period, self.last[1], self.first[1],
                        self.last[2], self.first[2]))
        return out

    def reversals(self) -> int:
        """``sum(s != roll(s, 1))`` of the significant samples' signs (cyclic)."""
        if self.nan or not self.nsig:
            return 0
        return self.flips + int(np.sign(self.last[1]) != np.sign(self.first[1]))


def _row(aux, i):
    """A copy of row ``i`` of ``aux`` (a view would hold the whole block)."""
    return None if aux is None else np.array(aux[i])


@dataclass
class SeriesStats:
    """A series' first and last samples and its first least and greatest samples with
    their neighbours (``(index, value, previous, next)``, cyclic at the ends), the
    inputs there (SI), and its reversals (:func:`analytic.summary._reversals`)."""

    n: int
    first: float
    last: float
    second_last: float
    low: tuple
    high: tuple
    reversals: int = 0


class Extremes:
    """:class:`SeriesStats` of a series fed block by block (NaN samples ignored, as
    ``nanargmin``; the first of equal extremes, as ``argmin``)."""

    def __init__(self):
        self.n = 0
        self.first = self.last = self.second_last = math.nan
        self.best = {-1: None, 1: None}  # sign -> [index, value, previous, next]

    def feed(self, y: np.ndarray) -> None:
        y = np.asarray(y, float)
        k = len(y)
        if not k:
            return
        for s in (-1, 1):
            b = self.best[s]
            if b is not None and b[3] is None:  # the sample after it opens this block
                b[3] = float(y[0])
            with np.errstate(invalid="ignore"):
                if np.all(np.isnan(y)):
                    continue
                j = int(np.nanargmin(y) if s < 0 else np.nanargmax(y))
            v = float(y[j])
            if b is None or (v < b[1] if s < 0 else v > b[1]):
                prev = float(y[j - 1]) if j else (self.last if self.n else None)
                nxt = float(y[j + 1]) if j + 1 < k else None
                self.best[s] = [self.n + j, v, prev, nxt]
        if self.n == 0:
            self.first = float(y[0])
        self.second_last = float(y[-2]) if k > 1 else self.last
        self.last = float(y[-1])
        self.n += k

    def stats(self, reversals: int = 0) -> SeriesStats:
        out = []
        for s in (-1, 1):
            b = self.best[s]
            if b is None:
                out.append((0, math.nan, math.nan, math.nan))
                continue
            prev = self.last if b[2] is None else b[2]  # index 0: the last sample
            nxt = self.first if b[3] is None else b[3]  # the last index: the first
            out.append((b[0], b[1], prev, nxt))
        return SeriesStats(self.n, self.first, self.last, self.second_last, out[0], out[1],
                           reversals)


def array_stats(y: np.ndarray, reversals: int = 0) -> SeriesStats:
    """:class:`SeriesStats` of a whole array (one block)."""
    e = Extremes()
    e.feed(y)
    return e.stats(reversals)


def _theta_deg(kin, b):
    return np.degrees(kin.theta[:, b])


def _moving(linkage):
    """The series the summary reads: ``{("slider", joint): s(kin), ("rocker", body
    index): theta deg(kin)}``, the bodies pivoted on the ground other than the input's."""
    from .mechanism import Revolute
    mech, topo = linkage.mech, linkage.topo
    out = {}
    for j in topo.prismatic:
        if j != topo.driver_joint:
            jn = topo.joint_names[j]
            out[("slider", jn)] = lambda k, jn=jn: k.slider(jn)[0]
    dj = mech.driver_joint
    driven = {dj.body_a, dj.body_b} - {mech.ground}
    for jt in mech.joints:
        if not isinstance(jt, Revolute) or mech.ground not in jt.bodies or jt.name == dj.name:
            continue
        body = jt.body_b if jt.body_a == mech.ground else jt.body_a
        if body not in driven:
            b = topo.body_names.index(body)
            out[("rocker", b)] = lambda k, b=b: _theta_deg(k, b)
    return out


def _det_rate(k):
    return k.determinant, np.full(k.n, np.nan)


class ArrayFacts:
    """The facts of an in-memory sweep, from its whole arrays."""

    def __init__(self, linkage, kin, frc):
        self.linkage, self.kin, self.frc = linkage, kin, frc
        self.x = np.asarray(kin.value, float)
        self.n = len(self.x)
        self._regular = None

    @property
    def regular(self) -> np.ndarray:
        if self._regular is None:
            self._regular = np.asarray(self.kin.condition < SINGULAR_CONDITION)
        return self._regular

    def x_at(self, idx) -> np.ndarray:
        return self.x[np.asarray(idx, int)]

    @property
    def bounds(self) -> tuple[float, float]:
        return float(np.min(self.x)), float(np.max(self.x))

    def distance(self, end: float) -> float:
        return float(np.min(np.abs(self.x - end)))

    def det_roots(self, periodic: bool) -> list[float]:
        return sign_changes(self.linkage, self.x, self.kin.determinant, periodic, _det_rate)

    def singular(self) -> list[tuple[float, float]]:
        cond = self.kin.condition
        return [(float(self.x[i]), float(cond[i])) for i in np.flatnonzero(~self.regular)]

    def turns(self, periodic: bool) -> dict:
        return turning_points(self.linkage, self.kin, periodic)

    def transmission(self, periodic: bool) -> list:
        return least_transmission(self.linkage, self.kin, periodic)

    def moving(self) -> dict:
        """key -> :class:`SeriesStats` of the summary's series (:func:`_moving`)."""
        out = {}
        for key, pick in _moving(self.linkage).items():
            y = np.asarray(pick(self.kin), float)
            out[key] = array_stats(y, _reversals(y))
        return out

    def near(self, key, roots) -> np.ndarray:
        """The series ``key``'s sample nearest each root (SI)."""
        y = np.asarray(_moving(self.linkage)[key](self.kin), float)
        return y[np.argmin(np.abs(self.x[None, :] - np.array(roots)[:, None]), axis=1)]

    @property
    def constant_speed(self) -> bool:
        return bool(np.all(self.kin.acceleration == 0))

    def rates_at(self, i: int) -> tuple[float, float]:
        return float(self.kin.velocity[i]), float(self.kin.acceleration[i])

    def effort(self) -> SeriesStats | None:
        """|drive effort| over the regular samples (NaN at the singular ones)."""
        if self.frc is None:
            return None
        return array_stats(np.where(self.regular, np.abs(self.frc.effort), np.nan))

    def power_peaks(self, terms) -> tuple[float, float, float, float]:
        """Over the regular samples: the largest |power residual|, power terms
        (``terms(kin)``), |drive power| and |load power|."""
        r, f = self.regular, self.frc
        t = self.kin.series(terms)[r]
        return (float(np.max(np.abs(f.power_residual[r]))),
                float(np.max(t)) if t.size else 0.0,
                float(np.max(np.abs(f.power[r]))), float(np.max(np.abs(f.load_power[r]))))


def _reversals(y: np.ndarray) -> int:
    """Reversals of a sampled periodic series (see :func:`diff_tracker`)."""
    t = diff_tracker()
    d = np.diff(np.concatenate([y, y[:1]]))
    t.feed(None, d)
    return t.reversals()


def diff_tracker() -> SignTracker:
    """A :class:`SignTracker` of a series' steps ``y[i+1] - y[i]`` (the last step back
    to the first sample), for reversals: steps within 1e-9 of the largest are not
    counted."""
    return SignTracker(0.0, keep=False)


class StreamFacts:
    """The facts of a streamed sweep, gathered block by block (:meth:`feed`), with the
    same answers as :class:`ArrayFacts` of the whole arrays.  ``grid``: the inputs
    (:class:`analytic.sweep.InputGrid`); ``ends``: the feasible range's ends whose
    distance to the nearest input the events ask; ``terms``: the summary's power terms
    per sample (:func:`analytic.summary._power_terms`)."""

    def __init__(self, linkage, grid, velocity: float, acceleration: float, forces: bool,
                 ends=(), terms=None):
        self.linkage, self.grid = linkage, grid
        self.vel, self.acc = float(velocity), float(acceleration)
        self.n = 0
        self.lo, self.hi = math.inf, -math.inf
        self._dist = {float(e): math.inf for e in ends}
        self._sing: list[tuple[float, float]] = []
        self._det = SignTracker()
        self._xr, self._xr_last, self._nreg = [], math.nan, 0  # regular inputs
        self._rates: dict = {}  # key -> (tracker, rate)
        self._moving = {k: [Extremes(), diff_tracker(), None] for k in _moving(linkage)}
        self._least: dict = {}  # joint -> [folded, index, raw]
        self._effort = Extremes() if forces else None
        self._terms, self._power = terms, [0.0, 0.0, 0.0, 0.0] if forces else None
        self._memo: dict = {}

    # -- gathering ---------------------------------------------------------------------
    def feed(self, kin, frc) -> None:
        """One block's kinematics and forces (the next ``kin.n`` inputs)."""
        x = np.asarray(kin.value, float)
        if not len(x):
            return
        self.lo, self.hi = min(self.lo, float(np.min(x))), max(self.hi, float(np.max(x)))
        for e in self._dist:
            self._dist[e] = min(self._dist[e], float(np.min(np.abs(x - e))))
        cond = kin.condition
        regular = np.asarray(cond < SINGULAR_CONDITION)
        self._sing += [(float(x[i]), float(cond[i])) for i in np.flatnonzero(~regular)]
        self._det.feed(x, kin.determinant)
        self._feed_rates(kin, x, regular)
        for key, pick in _moving(self.linkage).items():
            ext, rev, last = self._moving[key]
            y = np.asarray(pick(kin), float)
            ext.feed(y)
            rev.feed(None, np.diff(y if last is None else np.concatenate(([last], y))))
            self._moving[key][2] = float(y[-1])
        for jn, mu in kin.transmission.items():
            mu = np.asarray(mu, float)
            i = int(np.argmin(np.minimum(mu, 180.0 - mu)))
            f = min(float(mu[i]), 180.0 - float(mu[i]))
            best = self._least.get(jn)
            if best is None or f < best[0]:
                self._least[jn] = [f, self.n + i, float(mu[i])]
        if frc is not None:
            self._effort.feed(np.where(regular, np.abs(frc.effort), np.nan))
            if regular.any():
                p = self._power
                t = np.asarray(self._terms(kin))[regular]
                p[0] = max(p[0], float(np.max(np.abs(frc.power_residual[regular]))))
                p[1] = max(p[1], float(np.max(t)) if t.size else 0.0)
                p[2] = max(p[2], float(np.max(np.abs(frc.power[regular]))))
                p[3] = max(p[3], float(np.max(np.abs(frc.load_power[regular]))))
        self.n += len(x)

    def _feed_rates(self, kin, x, regular, only=None) -> None:
        xr = x[regular]
        if only is None and len(xr):
            self._xr[:2] = (self._xr[:2] + [float(v) for v in xr[:2]])[:2]
            self._xr_last, self._nreg = float(xr[-1]), self._nreg + len(xr)
        aux = np.degrees(kin.theta[regular]) if len(xr) else None
        for key, (y, scale, rate) in rate_series(self.linkage, kin, regular).items():
            if only is not None and key not in only:
                continue
            if key not in self._rates:
                self._rates[key] = (SignTracker(scale), rate)
            self._rates[key][0].feed(xr, y, aux)

    def finish(self) -> None:
        """After the last block: close the cyclic steps of the summary's series."""
        for ext, rev, _ in self._moving.values():
            if ext.n:
                rev.feed(None, np.array([ext.first - ext.last]))

    def refeed_keys(self) -> list:
        """The series whose sign changes need a second pass (:attr:`SignTracker.exact`)."""
        keys = [k for k, (t, _) in self._rates.items() if not t.exact]
        if not self._det.exact:
            keys.append("det")
        keys += [k for k, (_, rev, _) in self._moving.items() if not rev.exact]
        return keys

    def start_refeed(self, keys) -> None:
        """Trackers for ``keys`` against their final peaks, fed by :meth:`refeed`."""
        self._again = set(keys)
        self._carry = {}
        for k in keys:
            if k == "det":
                self._det = SignTracker(self._det.final_scale)
            elif k in self._rates:
                t, r = self._rates[k]
                self._rates[k] = (SignTracker(t.final_scale), r)
            else:
                rev = self._moving[k][1]
                self._moving[k][1] = SignTracker(rev.final_scale, keep=False)

    def refeed(self, kin) -> None:
        """One block of the second pass (kinematics only)."""
        x = np.asarray(kin.value, float)
        regular = np.asarray(kin.condition < SINGULAR_CONDITION)
        if "det" in self._again:
            self._det.feed(x, kin.determinant)
        self._feed_rates(kin, x, regular, only=self._again)
        for key, pick in _moving(self.linkage).items():
            if key in self._again:
                y = np.asarray(pick(kin), float)
                last = self._carry.get(key)
                self._moving[key][1].feed(
                    None, np.diff(y if last is None else np.concatenate(([last], y))))
                self._carry[key] = float(y[-1])

    def finish_refeed(self) -> None:
        for key in self._again:
            if key in self._moving:
                ext, rev, _ = self._moving[key]
                rev.feed(None, np.array([ext.first - ext.last]))

    # -- the answers (as ArrayFacts) --------------------------------------------------
    def x_at(self, idx) -> np.ndarray:
        return self.grid.at(idx)

    @property
    def bounds(self) -> tuple[float, float]:
        return self.lo, self.hi

    def distance(self, end: float) -> float:
        return self._dist[float(end)]

    def det_roots(self, periodic: bool) -> list[float]:
        if self.n < 2:
            return []
        t = self._det
        x0, x1, xl = (float(v) for v in self.grid.at([0, 1, -1]))
        period = (xl - x0) + (x1 - x0) if periodic else 0.0
        br = [p[:4] for p in t.brackets(periodic, period)]
        zero = ROUND_OFF * max(t.peak, 0.0)
        return locate_brackets(self.linkage, {0: br}, {0: _det_rate}, x0, period, zero)[0]

    def singular(self) -> list[tuple[float, float]]:
        return list(self._sing)

    def turns(self, periodic: bool) -> dict:
        key = ("turns", periodic)
        if key in self._memo:
            return self._memo[key]
        xr = self._xr
        if self._nreg < 2:  # fewer than two regular samples
            out = {k: [] for k in self._rates}
        else:
            period = (self._xr_last - xr[0]) + (xr[1] - xr[0]) if periodic else 0.0
            out = locate_brackets(
                self.linkage, {k: [p[:4] for p in t.brackets(periodic, period)]
                               for k, (t, _) in self._rates.items()},
                {k: r for k, (_, r) in self._rates.items()}, xr[0], period)
        self._memo[key] = out
        return out

    def transmission(self, periodic: bool) -> list:
        key = ("transmission", periodic)
        if key not in self._memo:
            least = [(jn, i, raw) for jn, (_, i, raw) in self._least.items()]
            self._memo[key] = locate_least_transmission(self.linkage, least, self.n,
                                                        self.grid.at, periodic)
        return self._memo[key]

    def moving(self) -> dict:
        return {k: ext.stats(rev.reversals()) for k, (ext, rev, _) in self._moving.items()}

    def near(self, key, roots) -> np.ndarray:
        """The series ``key`` (a rocker's angle, deg) at the sample nearest each root:
        the nearer end of the root's bracket (where the rate changed sign)."""
        b = key[1]
        g = int(self.linkage.topo.group_of[b])
        t = self._rates[("group", g)][0]
        ends = [(p[0], p[4]) for p in t.pairs] + [(p[1], p[5]) for p in t.pairs]
        if t.first is not None:
            ends += [(t.first[0], t.first[2]), (t.last[0], t.last[2])]
        xs = np.array([e[0] for e in ends])
        out = []
        for r in roots:
            d = np.abs(xs - r)
            if self.grid.kind == "turn":  # a periodic sweep's closing bracket
                d = np.minimum(d, np.abs(np.abs(xs - r) - 2 * math.pi))
            out.append(float(ends[int(np.argmin(d))][1][b]))
        return np.array(out)

    @property
    def constant_speed(self) -> bool:
        return self.acc == 0

    def rates_at(self, i: int) -> tuple[float, float]:
        return self.vel, self.acc

    def effort(self) -> SeriesStats | None:
        return None if self._effort is None else self._effort.stats()

    def power_peaks(self, terms) -> tuple[float, float, float, float]:
        return tuple(self._power)
