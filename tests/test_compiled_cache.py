"""numba's cache and the sources it was compiled from (nav.compiled.drop_stale_compilations)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

CALLEE = "from numba import njit\n\n\n@njit(cache=True, inline='always')\ndef value():\n    return {}\n"
CALLER = "from numba import njit\n\nfrom .callee import value\n\n\n@njit(cache=True)\ndef run():\n    return value()\n"
GUARD = "from nav.compiled import drop_stale_compilations\n\nfrom . import callee, caller\n\n" \
        "drop_stale_compilations([callee, caller])\n"


def package(root: Path, name: str, guarded: bool) -> Path:
    """A package whose cached ``caller.run`` inlines ``callee.value`` (1.0), its cache guarded or not."""
    folder = root / name
    folder.mkdir()
    (folder / "__init__.py").write_text(GUARD if guarded else "")
    (folder / "callee.py").write_text(CALLEE.format(1.0))
    (folder / "caller.py").write_text(CALLER)
    return folder


def run(root: Path, name: str) -> tuple[float, bool]:
    """``caller.run()`` in a new process (a fresh start, with whatever numba cached), and whether its compiled
    code came from the cache."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root), str(Path(__file__).resolve().parents[1])])}
    out = subprocess.run([sys.executable, "-c", f"import {name}.caller as c; print(c.run(), sum(c.run.stats.cache_hits.values()))"], env=env,
                         capture_output=True, text=True, check=True)
    value, hits = out.stdout.split()
    return float(value), int(hits) > 0


def edit_callee(folder: Path, value: float) -> None:
    """Change the callee's source, its time stamp certainly moved (numba keys a file on time stamp and size)."""
    path = folder / "callee.py"
    stat = path.stat()
    path.write_text(CALLEE.format(value))
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))


@pytest.mark.parametrize("guarded", [False, True])
def test_a_changed_callee_reaches_its_cached_caller_only_through_the_guard(tmp_path, guarded):
    """numba keeps a caller's cached code when only an inlined callee's file changes (the unguarded package
    runs the old callee: the trap this guards against); with drop_stale_compilations the caller runs the new
    callee, and an unchanged package keeps its cache."""
    name = f"cachedpkg_{'guarded' if guarded else 'plain'}"
    folder = package(tmp_path, name, guarded)
    assert run(tmp_path, name) == (1.0, False)
    assert run(tmp_path, name) == (1.0, True)
    edit_callee(folder, 2.0)
    assert run(tmp_path, name) == ((2.0, False) if guarded else (1.0, True))
    assert run(tmp_path, name) == ((2.0, True) if guarded else (1.0, True))
