"""What numba-compiled code needs from its callers and from its cache.

- :func:`kernel_array`: the arrays handed to a compiled kernel. numba compiles a kernel once per tuple of argument
  types, and an array's type holds its layout and read-only flag: a strided or read-only input (a broadcast view,
  a memory-mapped file) would compile it again (for nav's filter, 50-70 s of CPU).
- :func:`drop_stale_compilations`: numba's cache (``cache=True``) keys each function's compiled code on its own
  source file's time stamp and size. A function that inlines or calls another module's function keeps its
  compiled code when only that module changes, and goes on running the old code. Calling this after importing
  a package's compiled modules drops their cached code whenever any of their sources differs from the sources
  it was compiled from.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from types import ModuleType

import numpy as np
from numba.core.dispatcher import Dispatcher

SOURCES_STAMP = "compiled-sources.sha256"  # file beside the cached code: the digest of the sources it came from


def kernel_array(x, dtype, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``x`` (broadcast to ``shape`` when given) as a C-contiguous, writable array of ``dtype``; a copy only when it
    is not one already (see the module docstring)."""
    x = np.asarray(x, dtype)
    if shape is not None:
        x = np.broadcast_to(x, shape)
    return np.require(x, dtype, ("C", "W"))


def sources_digest(modules: list[ModuleType]) -> str:
    """SHA-256 over the source files of ``modules``, in the order given."""
    digest = hashlib.sha256()
    for module in modules:
        digest.update(Path(module.__file__).read_bytes())
    return digest.hexdigest()


def drop_stale_compilations(modules: list[ModuleType]) -> bool:
    """Empty the numba cache of every cached function of ``modules`` when their sources (all of them together,
    :func:`sources_digest`) differ from those the cache was written for, and record the new digest beside it
    (:data:`SOURCES_STAMP`). Call it once the modules are imported, before any of their functions runs.

    Returns
    -------
    True when cached code was dropped (or there was no record of its sources).
    """
    cached = [obj for module in modules for obj in vars(module).values()
              if isinstance(obj, Dispatcher) and obj._cache.cache_path is not None and obj.__module__ == module.__name__]
    if not cached:
        return False
    stamp = Path(cached[0]._cache.cache_path) / SOURCES_STAMP
    digest = sources_digest(modules)
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:  # no record yet: a fresh cache, or one written before the record existed
        pass
    for dispatcher in cached:
        dispatcher._cache.flush()
    try:
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest)
    except OSError:  # a read-only cache: numba then compiles in memory
        pass
    return True
