"""``xval tune``: the cheapest settings of an engine whose verdict passes at a stated
tolerance, found by a search over measured runs (:mod:`reports.tune.search`), verified
by a fresh run and written back as a settings file or a tuned MJCF
(:mod:`reports.tune.tune`, :mod:`reports.tune.model`)."""

from reports.tune.measure import TuneCase
from reports.tune.tune import TuneResult, tune

__all__ = ["TuneCase", "TuneResult", "tune"]
