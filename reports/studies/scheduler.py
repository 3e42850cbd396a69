"""A priority front for the report's process pool (or Dask executor).

A plain pool runs tasks first in, first out: the figures of a case, submitted when its
engine runs are in, would wait behind a hundred study runs while the reader waits for
the verdict's pictures.  :class:`PriorityExecutor` keeps at most ``slots`` tasks in the
pool and hands it the most urgent waiting task whenever one finishes (by
:data:`PRIORITY` of the task function's name, then submission order).
"""

from __future__ import annotations

import heapq
import itertools
import threading
from concurrent.futures import Executor, Future

#: Lower runs first: the long hard-case runs are the full report's critical path; then
#: the verdict runs, the figures of cases whose runs are in, the Pareto plots, the
#: scene study (one serial task of seconds), then the many short change-point and grid
#: runs, which pack the end of the run onto both workers.  The report runs the hard cases' other
#: tasks in a lane of their own (:meth:`PriorityExecutor.submit_at`) ahead of the grids.
PRIORITY = {"long_run_task": 0, "_task_entry": 1, "_figure_task": 2, "_pareto_task": 3,
            "_scene_task": 3.5, "change_point_task": 4, "grid_task": 5}


class PriorityExecutor(Executor):
    """``submit`` queues; a dispatcher thread feeds ``inner`` up to ``slots`` at a time."""

    def __init__(self, inner: Executor, slots: int, priority: dict | None = None):
        self.inner, self.slots = inner, max(1, int(slots))
        self.priority = PRIORITY if priority is None else priority
        self._heap: list = []
        self._seq = itertools.count()
        self._cv = threading.Condition()
        self._inflight = 0
        self._closed = False
        self._thread = threading.Thread(target=self._dispatch, name="report-dispatch",
                                        daemon=True)
        self._thread.start()

    def submit(self, fn, /, *args, **kwargs):
        return self.submit_at(self.priority.get(getattr(fn, "__name__", ""), 9), fn, *args,
                              **kwargs)

    def submit_at(self, p: float, fn, /, *args, **kwargs):
        f: Future = Future()
        with self._cv:
            if self._closed:
                raise RuntimeError("cannot submit after shutdown")
            heapq.heappush(self._heap, (p, next(self._seq), fn, args, kwargs, f))
            self._cv.notify_all()
        return f

    def _dispatch(self):
        while True:
            with self._cv:
                while not self._closed and not (self._heap and self._inflight < self.slots):
                    self._cv.wait()
                if self._closed and not self._heap:
                    return
                if not self._heap or self._inflight >= self.slots:
                    self._cv.wait(0.05)
                    continue
                _, _, fn, args, kwargs, f = heapq.heappop(self._heap)
                if not f.set_running_or_notify_cancel():
                    continue
                self._inflight += 1
            try:
                inner = self.inner.submit(fn, *args, **kwargs)
            except BaseException as e:  # noqa: BLE001 - the task's own failure
                self._finish(f, None, e)
                continue
            inner.add_done_callback(lambda g, f=f: self._finish(f, g, None))

    def _finish(self, f: Future, g, exc):
        with self._cv:
            self._inflight -= 1
            self._cv.notify_all()
        if exc is None:
            exc = g.exception()
        if exc is not None:
            f.set_exception(exc)
        else:
            f.set_result(g.result())

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False):
        with self._cv:
            if cancel_futures:
                for *_, f in self._heap:
                    f.cancel()
                self._heap.clear()
            self._closed = True
            self._cv.notify_all()
        if wait:
            self._thread.join()


__all__ = ["PRIORITY", "PriorityExecutor", "dask_executor"]


def dask_executor(address: str) -> Executor:
    """The executor of a Dask distributed client connected to the scheduler at
    ``address`` (its ``client_to_close`` attribute: the client, to close after); a
    missing ``distributed`` package or an unreachable scheduler is one line
    (:class:`analytic.LinkageError`)."""
    from analytic import LinkageError
    try:
        from distributed import Client
    except ImportError:
        raise LinkageError("--dask needs the 'distributed' package "
                           "(pip install 'dask[distributed]')") from None
    try:
        client = Client(address)
    except OSError as e:  # no scheduler there: a user error, one line
        raise LinkageError(f"--dask: cannot reach a scheduler at {address!r}: {e}") from None
    ex = client.get_executor()
    ex.client_to_close = client
    return ex
