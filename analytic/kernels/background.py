"""Compile a kernel in a background process, while the numpy path answers.

:func:`start` writes the kernel's module and the argument types of its one
specialisation (:meth:`analytic.fused.FusedKernel.sample_args`, a call at no
configurations) and starts ``python -m analytic.kernels.background MODULE ARGS`` in its
own session: it compiles the kernel into numba's on-disk cache and marks it ready
(:func:`analytic.kernels.cache.mark_ready`), so the next call that finds it loads it in a
fraction of a second.  The process outlives the one that started it (a command that
solved one point still leaves the kernel compiled for the next).  One per structure
and process; none while a ``<name>.compiling`` marker younger than :data:`STALE_S` says
another process is compiling it.  ``XVAL_BACKGROUND_COMPILE=0`` turns it off.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import time
from pathlib import Path

#: a compile marker older than this is taken as left by a process that died (the
#: six-bar compiles in 10-15 s at load 1, up to 60 s on a loaded 2-core machine)
STALE_S = 300.0
_STARTED: dict[str, subprocess.Popen | None] = {}


def start(fk) -> bool:
    """Start compiling ``fk``'s kernel in the background; whether a process started."""
    from .cache import cache_dir, write_source
    name = fk.name
    if name in _STARTED:
        p = _STARTED[name]
        if p is not None:
            p.poll()  # reap it when done
        return False
    _STARTED[name] = None
    if os.environ.get("XVAL_BACKGROUND_COMPILE", "1").strip().lower() in ("0", "off", "no"):
        return False
    try:
        d = cache_dir()
    except OSError:  # no writable cache: the numpy path goes on
        return False
    lock = d / f"{name}.compiling"
    try:
        if time.time() - lock.stat().st_mtime < STALE_S:
            return False
    except OSError:
        pass
    try:
        path = write_source(fk.source.source)
        args = d / f"{name}.{os.getpid()}.args"
        args.write_bytes(pickle.dumps(fk.sample_args()))
        lock.write_text(str(os.getpid()))
        root = str(Path(__file__).resolve().parents[2])
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            filter(None, (root, os.environ.get("PYTHONPATH")))))
        _STARTED[name] = subprocess.Popen(
            [sys.executable, "-m", "analytic.kernels.background", str(path), str(args)],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True, env=env, cwd=str(d))
    except OSError:  # a full disk, no interpreter: the numpy path goes on
        for p in (d / f"{name}.{os.getpid()}.args", lock):
            try:
                p.unlink()
            except OSError:
                pass
        return False
    return True


def _main(module: str, args: str) -> int:
    from .cache import _load, mark_ready
    name = Path(module).stem
    lock = Path(module).with_name(f"{name}.compiling")
    try:
        mod = _load(Path(module).read_text())
        sample = pickle.loads(Path(args).read_bytes())
        if sample is not None:  # None: an explicit signature compiled it at import
            mod.kernel(*sample)
        mark_ready(name, mod.kernel)
        return 0
    finally:
        for p in (Path(args), lock):
            try:
                p.unlink()
            except OSError:
                pass


if __name__ == "__main__":
    sys.exit(_main(*sys.argv[1:3]))
