"""The exact integration's wall clock: a limit the user sets, and progress.

The right-hand side of the equation of motion calls :meth:`WallClock.check` at every
evaluation (a few per step, each well under a millisecond), so a limit is honoured
within one evaluation of its value, not once per output sample; event location does
the same between root findings, and the sampling of the trajectory
(:meth:`analytic.free_motion.FreeTrajectory.at` with ``clock=``) between chunks of
:data:`SAMPLE_CHUNK` samples (:meth:`WallClock.check_samples`).  Progress goes to
callbacks (the library prints nothing; the command line shows it on a terminal).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from ..errors import LinkageError
from ..motion_spec import MAX_WALL_LIMIT  # with the other ranges

#: Seconds between two progress reports.
PROGRESS_EVERY_S = 0.25
#: Samples reconstructed between two checks of the clock: ~0.05-0.3 s of work at the
#: measured 1e6 samples in 40-140 s (a check is ~1 us: free at this spacing), and it
#: bounds the sampling's working arrays to this many rows at a time.
SAMPLE_CHUNK = 2000


class WallLimitError(LinkageError):
    """The exact integration ran past the user's wall-clock limit."""


def check_wall_limit(limit: float | None) -> None:
    """``None`` (no limit) or a number above 0 and at most :data:`MAX_WALL_LIMIT` s."""
    if limit is None:
        return
    if isinstance(limit, bool) or not isinstance(limit, int | float) \
            or not 0.0 < float(limit) <= MAX_WALL_LIMIT:
        raise LinkageError(f"wall_limit = {limit!r}: must be above 0 and at most "
                           f"{MAX_WALL_LIMIT:g} s (one day)")


class WallClock:
    """Counts wall-clock time from construction; ``limit`` s (None: none); ``name`` says
    what runs (file and mechanism), for the message.  ``progress(t, duration)`` (s) is
    called during the integration, ``sample_progress(done, total)`` (samples) during
    the sampling, each at most every :data:`PROGRESS_EVERY_S`."""

    def __init__(self, name: str, duration: float, limit: float | None = None,
                 progress: Callable[[float, float], None] | None = None,
                 sample_progress: Callable[[int, int], None] | None = None,
                 now: Callable[[], float] = time.monotonic):
        check_wall_limit(limit)
        self.name, self.duration, self.limit, self.progress = name, duration, limit, progress
        self.sample_progress = sample_progress
        self._now = now  # a test's fake clock
        self.start = self._last = now()
        self.t = 0.0
        self.switches = 0

    def check(self, t: float | None = None) -> None:
        """Raise :class:`WallLimitError` past the limit; report progress now and then."""
        now = self._now()
        if t is not None:
            self.t = max(self.t, t)
        if self.limit is not None and now - self.start > self.limit:
            raise WallLimitError(
                f"{self.name}: the exact integration reached the wall-clock "
                f"limit of {self.limit:g} s at t = {self.t:.6g} s of {self.duration:g} s "
                f"({self.switches} coordinate switches so far); raise --wall-limit or "
                "shorten --duration")
        if self.progress is not None and now - self._last > PROGRESS_EVERY_S:
            self._last = now
            self.progress(self.t, self.duration)

    def check_samples(self, done: int, total: int) -> None:
        """Between chunks of the sampling: raise :class:`WallLimitError` past the limit
        (the same limit and message form as the integration's, with the samples done of
        ``total``); report ``sample_progress`` now and then."""
        now = self._now()
        if self.limit is not None and now - self.start > self.limit:
            raise WallLimitError(
                f"{self.name}: sampling the exact trajectory reached the wall-clock "
                f"limit of {self.limit:g} s at {done:,} of {total:,} samples "
                f"(the integration of {self.duration:g} s had finished); raise --wall-limit "
                "or lower --samples")
        if self.sample_progress is not None and now - self._last > PROGRESS_EVERY_S:
            self._last = now
            self.sample_progress(done, total)
