"""The commands that show one linkage: ``xval plot``, ``xval animate``, ``xval view``.

Registered after the engine commands (:mod:`reports.cli_engines`); each lives in its own
module and imports matplotlib or an engine only when run.
"""

from __future__ import annotations


def register(sub) -> None:
    from . import plot_cmd
    plot_cmd.register(sub)
    try:
        from . import animate
    except ImportError:  # pragma: no cover - not built yet
        return
    animate.register(sub)
    try:
        from . import view_cmd
    except ImportError:  # pragma: no cover - not built yet
        return
    view_cmd.register(sub)
