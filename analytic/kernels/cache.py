"""Where kernels live: generated modules and numba's compiled cache on disk, and the
modules imported in this process (:mod:`analytic.fused` compiles and calls them,
:mod:`analytic.kernels.background` compiles them in another process; both import this
lower module, neither the other)."""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from pathlib import Path

#: kernel modules imported in this process: module name -> module
_MODULES: dict[str, object] = {}


def cache_dir() -> Path:
    """Where generated kernel modules and numba's compiled cache live:
    ``$XVAL_KERNEL_CACHE``, else ``$XDG_CACHE_HOME/linkage-xval/kernels``."""
    d = os.environ.get("XVAL_KERNEL_CACHE")
    if not d:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(Path.home(), ".cache")
        d = os.path.join(base, "linkage-xval", "kernels")
    p = Path(d)
    p.mkdir(parents=True, exist_ok=True)
    return p


def module_name(source: str) -> str:
    """The generated module's name: its content hash."""
    return "xval_kernel_" + hashlib.sha256(source.encode()).hexdigest()[:20]


def write_source(source: str) -> Path:
    """The generated module's file (written once under its content hash; numba keys its
    on-disk cache on the file's time stamp, so an unchanged file is never rewritten)."""
    path = cache_dir() / f"{module_name(source)}.py"
    if not path.is_file() or path.read_text() != source:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(source)
        os.replace(tmp, path)
    return path


def _load(source: str):
    """Import the generated module (imports numba)."""
    name = module_name(source)
    if name in _MODULES:
        return _MODULES[name]
    path = write_source(source)
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    _MODULES[name] = mod
    return mod


def mark_ready(name: str, fn) -> None:
    """Record that ``fn`` (a kernel's dispatcher, after a call) is in numba's on-disk
    cache: ``<name>.ready`` holds the path of numba's index file, which
    :func:`on_disk` checks (an emptied numba cache makes the marker stale, not wrong)."""
    try:
        index = os.path.abspath(fn._cache._cache_file._index_path)  # numba 0.5x-0.6x
    except AttributeError:
        return
    if os.path.exists(index):
        marker = cache_dir() / f"{name}.ready"
        tmp = marker.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(index)
        os.replace(tmp, marker)


def on_disk(name: str) -> bool:
    """Whether the kernel module ``name`` is compiled in numba's on-disk cache (a
    process then loads it instead of compiling it)."""
    try:
        index = (cache_dir() / f"{name}.ready").read_text()
    except OSError:
        return False
    numba_dir = os.environ.get("NUMBA_CACHE_DIR")
    if numba_dir and not index.startswith(os.path.abspath(numba_dir)):
        return False  # compiled into another numba cache than this process reads
    return os.path.exists(index)
