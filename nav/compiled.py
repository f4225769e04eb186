"""What numba-compiled code needs from its callers and from its cache.

- :func:`kernel_array`: the arrays handed to a compiled kernel. numba compiles a kernel once per tuple of argument
  types, and an array's type holds its layout and read-only flag: a strided or read-only input (a broadcast view,
  a memory-mapped file) would compile it again (for nav's filter, 50-70 s of CPU).
- :func:`key_cache_to_sources`: numba's cache (``cache=True``) keys each function's compiled code on its own
  source file alone. A function that inlines or calls another module's function kept its compiled code when only
  that module changed, and went on running the old code. Keyed on the sources of every module of its package
  instead, each process saves and accepts only code compiled from the sources it imported.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from types import ModuleType

import numpy as np
from numba.core.dispatcher import Dispatcher


def kernel_array(x, dtype, shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``x`` (broadcast to ``shape`` when given) as a C-contiguous, writable array of ``dtype``; a copy only when it
    is not one already (see the module docstring)."""
    x = np.asarray(x, dtype)
    if shape is not None and x.shape != tuple(shape):
        x = np.broadcast_to(x, shape)
    return np.require(x, dtype, ("C", "W"))


def sources_digest(modules: list[ModuleType]) -> str:
    """SHA-256 over the source files of ``modules``, in the order given."""
    digest = hashlib.sha256()
    for module in modules:
        digest.update(Path(module.__file__).read_bytes())
    return digest.hexdigest()


def key_cache_to_sources(modules: list[ModuleType]) -> None:
    """Key the numba cache of every cached function defined in ``modules`` on the sources of all of them
    (:func:`sources_digest`) as well as its own file. Call it once the modules are imported, before any of their
    functions runs.

    numba stamps an index with its function's source stamp and ignores an index whose stamp differs from its
    own; the digest is added to that stamp (a private attribute of numba's cache file: tests/test_compiled_cache.py
    pins the behaviour). Nothing is written here, and a process still running older sources saves code under
    their stamp, which a process with the new sources does not load.
    """
    digest = sources_digest(modules)
    for module in modules:
        for obj in vars(module).values():
            if isinstance(obj, Dispatcher) and obj.__module__ == module.__name__ and obj._cache.cache_path is not None:
                cache_file = obj._cache._cache_file
                cache_file._source_stamp = (cache_file._source_stamp, digest)
