"""The report's priority queue in front of its pool: most urgent first, every result
and exception delivered, nothing lost at shutdown."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor, wait

import pytest

from reports.studies.scheduler import PriorityExecutor


def test_most_urgent_first_and_every_result():
    gate = threading.Event()
    order = []

    def blocker():
        gate.wait(5)
        return "first"

    def job(tag):
        order.append(tag)
        return tag

    def fail():
        raise ValueError("boom")

    with ThreadPoolExecutor(1) as pool:
        ex = PriorityExecutor(pool, slots=1, priority={"blocker": 0})
        f0 = ex.submit(blocker)  # occupies the only slot while the rest queue up
        fs = [ex.submit_at(p, job, tag) for p, tag in ((5, "late"), (1, "soon"), (3, "mid"))]
        bad = ex.submit_at(2, fail)
        gate.set()
        wait([f0, bad, *fs], timeout=10)
        ex.shutdown()
    assert f0.result() == "first"
    assert order == ["soon", "mid", "late"]
    assert [f.result() for f in fs] == ["late", "soon", "mid"]
    with pytest.raises(ValueError, match="boom"):
        bad.result()


def test_shutdown_waits_for_queued_tasks():
    with ThreadPoolExecutor(2) as pool:
        ex = PriorityExecutor(pool, slots=2)
        fs = [ex.submit(pow, 2, k) for k in range(20)]
        ex.shutdown(wait=True)
        assert [f.result(timeout=5) for f in fs] == [2 ** k for k in range(20)]
        with pytest.raises(RuntimeError):
            ex.submit(pow, 2, 2)
