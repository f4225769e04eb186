"""numba's cache and the sources it was compiled from (nav.compiled.key_cache_to_sources)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

CALLEE = "from numba import njit\n\n\n@njit(cache=True, inline='always')\ndef value():\n    return {}\n"
CALLER = "from numba import njit\n\nfrom .callee import value\n\n\n@njit(cache=True)\ndef run(x):\n" \
         "    return value() + x\n"
GUARD = "from nav.compiled import key_cache_to_sources\n\nfrom . import callee, caller\n\n" \
        "key_cache_to_sources([callee, caller])\n"
RUN = "import {name}.caller as c; print('imported', flush=True); input(); y = c.run({x}); " \
      "print(float(y), sum(c.run.stats.cache_hits.values()))"


def package(root: Path, name: str, guarded: bool) -> Path:
    """A package whose cached ``caller.run(x)`` inlines ``callee.value()`` (1.0), its cache keyed or not."""
    folder = root / name
    folder.mkdir()
    (folder / "__init__.py").write_text(GUARD if guarded else "")
    (folder / "callee.py").write_text(CALLEE.format(1.0))
    (folder / "caller.py").write_text(CALLER)
    return folder


def start(root: Path, name: str, x: str) -> subprocess.Popen:
    """A new process that imports the package, then waits for a line before it calls ``caller.run(x)``."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root), str(Path(__file__).resolve().parents[1])])}
    return subprocess.Popen([sys.executable, "-c", RUN.format(name=name, x=x)], env=env, text=True,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def result(process: subprocess.Popen) -> tuple[float, bool]:
    """(``caller.run(x)``, whether its compiled code came from the cache) of a started process."""
    out, err = process.communicate("\n", timeout=120)
    assert process.returncode == 0, err
    value, hits = out.splitlines()[-1].split()
    return float(value), int(hits) > 0


def run(root: Path, name: str, x: str = "1.0") -> tuple[float, bool]:
    return result(start(root, name, x))


def edit_callee(folder: Path, value: float) -> None:
    """Change the callee's source (its time stamp moved too, as numba's file check reads it first)."""
    path = folder / "callee.py"
    stat = path.stat()
    path.write_text(CALLEE.format(value))
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))


@pytest.mark.parametrize("guarded", [False, True])
def test_a_changed_callee_reaches_its_cached_caller_only_when_the_cache_is_keyed_to_the_package(tmp_path, guarded):
    """numba keeps a caller's cached code when only an inlined callee's file changes (the plain package runs the
    old callee from its cache: the trap); keyed to the package's sources, the caller is compiled again with the
    new callee, and the next process loads that from the cache."""
    name = f"cachedpkg_{'keyed' if guarded else 'plain'}"
    folder = package(tmp_path, name, guarded)
    assert run(tmp_path, name) == (2.0, False)
    assert run(tmp_path, name) == (2.0, True)
    edit_callee(folder, 2.0)
    assert run(tmp_path, name) == ((3.0, False) if guarded else (2.0, True))
    assert run(tmp_path, name) == ((3.0, True) if guarded else (2.0, True))


def test_a_process_still_running_the_old_sources_cannot_hand_its_code_to_a_new_one(tmp_path):
    """A process that imported the package before the callee changed (an open notebook, a pool worker) compiles
    and saves a new signature with the old callee; a process started after the change must not load it."""
    folder = package(tmp_path, "cachedpkg_race", guarded=True)
    assert run(tmp_path, "cachedpkg_race") == (2.0, False)
    old = start(tmp_path, "cachedpkg_race", "1")  # compiles run(int) when told
    assert old.stdout.readline().strip() == "imported"  # the old sources
    edit_callee(folder, 2.0)
    assert run(tmp_path, "cachedpkg_race") == (3.0, False)
    assert result(old) == (2.0, False)  # the old callee, saved to the cache under the old sources' key
    assert run(tmp_path, "cachedpkg_race", "1") == (3.0, False)
