"""Execution engine for experiments: run many independent tasks, store each result, resume after interruption.

What one run computes is up to the caller: :func:`run_tasks` takes a function ``fn(task) -> dict`` and a list of
tasks (JSON-serialisable dicts with a unique string ``"key"``) and runs them serially, on a local process pool or
on a Dask cluster, always with the same storage and resume semantics.

Storage
    Each run's result is written as soon as it finishes to ``out_dir/runs/<key>.json`` (a ``/`` in the key makes
    sub-folders), atomically (temporary file, then :func:`os.replace`). The file holds the task, a SHA-256 digest
    of the task's canonical JSON, of the source code that computes it (every file of the ``gaitsim`` and ``nav``
    packages: :func:`code_digest`) and of the content of every input file the task names (any string value that
    is the path of an existing file), and the result. A later call loads every stored result whose digest matches
    and computes only the others, so an interrupted experiment resumes where it stopped, while a changed task, a
    changed default in the code or an edited calibration file is recomputed rather than silently reused.

Determinism
    A run's result must depend on its task only -- never on the number of workers, the order runs finish in,
    or state left in a worker process by earlier runs. In particular every random draw comes from a numpy
    Generator seeded from a seed stored *in the task* (build it with :func:`derive_seed` when the tasks are
    made), never from a global generator or a per-worker seed. Every result, whether computed now or loaded,
    is returned as its JSON round trip, so a fresh and a resumed experiment return identical values.

Processes
    Local pools use the ``"forkserver"`` start method where the platform has it, else ``"spawn"``: workers never
    inherit a forked copy of the parent's numba, MuJoCo or thread state. Each worker dies with the process that
    started the pool (a watchdog thread polls it; on Linux the kernel also signals it when its parent dies), so a
    killed run leaves no worker behind; the forkserver and the resource tracker exit once their clients are gone. As a consequence ``fn`` must be
    picklable by reference (a function defined at the top level of an importable module), and a script that
    calls :func:`run_tasks` must guard its entry point with ``if __name__ == "__main__":``.
    Every worker, of the pool or of a Dask cluster, runs one numba and one BLAS thread (:func:`limit_worker_threads`):
    the experiment parallelises over tasks, and a BLAS thread pool inside each of several workers costs far more
    than it gains on a run's (N, 3) x (3, 3) products (on this project's busy 2-core machine one such product of
    84,000 rows took 23 ms with OpenBLAS's default threads and 0.5 ms with one). Every worker also keeps the
    memory it frees for reuse (:func:`keep_freed_memory`): fresh mappings cost page faults on every walk.
"""

from __future__ import annotations

import concurrent.futures
import ctypes
import functools
import hashlib
import json
import logging
import multiprocessing
import os
import pickle
import re
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from contextlib import closing
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from nav.files import write_text_atomic
from nav.storage import sha256

from gaitsim.errors import ScenarioError

__all__ = ["RunsFailedError", "derive_seed", "run_tasks"]

logger = logging.getLogger(__name__)

RESULT_FORMAT = "gaitsim.run-result/1"
"""Value of the ``"format"`` field of every stored result file."""

_KEY_SEGMENT = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.=+,-]*")

# (task index, True and the result's JSON text | False and the traceback text)
_Outcome = tuple[int, bool, str]


class RunsFailedError(RuntimeError):
    """Some runs of :func:`run_tasks` failed; the others finished and are stored.

    Attributes
    ----------
    failures : dict of str to str
        Key of each failed run -> the traceback text of its failure.
    """

    def __init__(self, message: str, failures: dict[str, str]):
        super().__init__(message)
        self.failures = failures


def derive_seed(base_seed: int, *names: str | int) -> int:
    """Seed for one run, derived from an experiment's base seed and the run's names.

    The value is the same in every process, on every platform and Python version (names are hashed with
    SHA-256, never with the salted built-in :func:`hash`, and mixed by :class:`numpy.random.SeedSequence`,
    whose output numpy keeps stable). Derive seeds when the tasks are built and store them in the tasks;
    a run must never draw its seed from a global generator or from worker state.

    Parameters
    ----------
    base_seed : int
        The experiment's seed (from its scenario file), >= 0.
    *names : str or int
        What identifies the run within the experiment, e.g. ``("before", 7)`` or ``("imu", "walk-3")``.
        ``"7"`` and ``7`` give different seeds; the order of the names matters.

    Returns
    -------
    int
        A seed in [0, 2**64) for :func:`numpy.random.default_rng`.

    Raises
    ------
    ValueError
        If ``base_seed`` is not a non-negative int or a name is neither str nor int.
    """
    if isinstance(base_seed, bool) or not isinstance(base_seed, (int, np.integer)) or base_seed < 0:
        raise ValueError(f"derive_seed: base_seed must be an int >= 0, got {base_seed!r}")
    words = []
    for name in names:
        if isinstance(name, str):
            tagged = b"s:" + name.encode("utf-8")
        elif isinstance(name, (int, np.integer)) and not isinstance(name, bool):
            tagged = b"i:" + str(int(name)).encode("ascii")
        else:
            raise ValueError(f"derive_seed: names must be str or int, got {name!r} ({type(name).__name__})")
        words.append(int.from_bytes(hashlib.sha256(tagged).digest()[:8], "little"))
    sequence = np.random.SeedSequence(entropy=int(base_seed), spawn_key=tuple(words))
    return int(sequence.generate_state(1, dtype=np.uint64)[0])


def run_tasks(
    fn: Callable[[dict], dict],
    tasks: Sequence[dict],
    out_dir: str | os.PathLike,
    *,
    workers: int | None = None,
    scheduler: Any = None,
    progress: bool = True,
) -> list[dict]:
    """Run ``fn`` on every task, storing each result as it finishes and reusing results already stored.

    Parameters
    ----------
    fn : callable
        ``fn(task) -> dict``, the computation of one run; its result must be JSON-serialisable (str keys;
        Python's JSON reads and writes NaN and infinities). For a pool or a cluster it must be picklable:
        a function defined at the top level of an importable module. It receives the task only, so
        everything a run depends on, its seed included, must be in the task.
    tasks : sequence of dict
        JSON-serialisable dicts, each with a unique string ``"key"`` made of ``/``-separated segments of
        letters, digits and ``_ . = + , -`` (not starting with ``.``), e.g. ``"before/run-007"``.
    out_dir : str or path-like
        Experiment folder; results go to ``out_dir/runs/<key>.json``.
    workers : int, optional
        Local worker processes; default :func:`os.cpu_count`. ``1`` runs the tasks serially in this process
        (no pool): use it to debug ``fn``. Must be left unset when ``scheduler`` is given.
    scheduler : str or distributed.Client, optional
        Run on a Dask cluster instead: a scheduler address (``"tcp://host:8786"``) or a connected
        ``distributed.Client``. Needs the optional ``distributed`` package (``pip install gaitsim[dask]``);
        the workers must be able to import ``fn``'s module. Results are stored by this process, so the
        workers need no shared file system.
    progress : bool
        Show a progress bar on stderr (when stderr is a terminal).

    Returns
    -------
    list of dict
        One result per task, in the order of ``tasks``.

    Raises
    ------
    ScenarioError
        For a task without a valid, unique ``"key"``, a task that is not JSON-serialisable, a bad
        ``workers`` or ``scheduler``; nothing is written then.
    TypeError
        If a pool is needed and ``fn`` cannot be pickled.
    ImportError
        If ``scheduler`` is given and ``distributed`` is not installed.
    RunsFailedError
        A RuntimeError raised after all other runs finished and were stored, if some runs failed: the
        message lists the failed keys and shows the first traceback; every traceback is logged as it
        happens and kept in the exception's ``failures`` attribute (dict key -> traceback text).
    """
    digests = _validate_tasks(tasks)
    _validate_backend(workers, scheduler)
    runs_dir = Path(out_dir) / "runs"
    paths = [_result_path(runs_dir, task["key"]) for task in tasks]

    results: list[dict | None] = [_load_stored(path, digest) for path, digest in zip(paths, digests)]
    pending = [index for index, result in enumerate(results) if result is None]
    if len(pending) < len(tasks):
        logger.info("%d of %d results loaded from %s", len(tasks) - len(pending), len(tasks), runs_dir)

    failures: dict[str, str] = {}
    bar = tqdm(
        total=len(tasks), initial=len(tasks) - len(pending), desc="runs", unit="run",
        file=sys.stderr, disable=None if progress else True,
    )
    with bar, closing(_outcomes(fn, tasks, pending, workers, scheduler)) as outcomes:
        for index, ok, text in outcomes:
            key = tasks[index]["key"]
            if ok:
                results[index] = _store(paths[index], tasks[index], digests[index], text)
            else:
                failures[key] = text
                bar.clear()  # keep the report off the bar's line
                logger.error("run %r failed:\n%s", key, text)
                bar.set_postfix(failed=len(failures))
            bar.update(1)

    if failures:
        raise RunsFailedError(_failure_message(failures, len(tasks), runs_dir), failures)
    return results


def _validate_tasks(tasks: Sequence[dict]) -> list[str]:
    """Check keys and serialisability of every task; return each task's SHA-256 digest (hex)."""
    if isinstance(tasks, (str, bytes, dict)) or not isinstance(tasks, Sequence):
        raise ScenarioError(f"tasks must be a list of dicts, got {type(tasks).__name__}")
    digests = []
    seen: dict[str, str] = {}
    directories: set[str] = set()
    for position, task in enumerate(tasks):
        if not isinstance(task, dict) or not isinstance(task.get("key"), str):
            raise ScenarioError(f"task #{position} must be a dict with a string 'key', got {task!r:.200}")
        key = task["key"]
        segments = key.split("/")
        if not all(_KEY_SEGMENT.fullmatch(segment) for segment in segments):
            raise ScenarioError(
                f"task #{position}: key {key!r} is not allowed; use '/'-separated segments of letters, digits "
                "and '_ . = + , -' that do not start with '.'"
            )
        if key.casefold() in seen:
            raise ScenarioError(
                f"task #{position}: key {key!r} repeats key {seen[key.casefold()]!r} (keys must be unique, "
                "also ignoring case, since each names a result file)"
            )
        seen[key.casefold()] = key
        directories.update("/".join(segments[:depth]).casefold() for depth in range(1, len(segments)))
        try:
            digests.append(task_digest(task))
        except (TypeError, ValueError) as exc:
            raise ScenarioError(f"task {key!r} is not JSON-serialisable: {exc}") from exc
    clashes = sorted(seen[folded] for folded in seen if f"{folded}.json" in directories)
    if clashes:
        raise ScenarioError(f"keys {clashes} end in '.json' where other keys use them as folders; rename them")
    return digests


def _validate_backend(workers: int | None, scheduler: Any) -> None:
    """Reject a worker count that is not a positive int or is given with a scheduler, and a bad scheduler."""
    if scheduler is not None and not isinstance(scheduler, str) and not hasattr(scheduler, "submit"):
        raise ScenarioError(
            f"scheduler must be a Dask scheduler address such as 'tcp://host:8786' or a distributed.Client, "
            f"got {scheduler!r}"
        )
    if workers is None:
        return
    if scheduler is not None:
        raise ScenarioError(
            f"workers={workers!r} applies to the local pool only; leave it unset with scheduler={scheduler!r} "
            "(the cluster's workers run the tasks)"
        )
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ScenarioError(f"workers must be an int >= 1 (1 = serial, in this process), got {workers!r}")


CODE_PACKAGES = ("gaitsim", "nav")  # packages whose source decides what a run computes
WATCHDOG_INTERVAL_S = 0.5  # s between a worker's checks that the process that started it is alive


@functools.lru_cache(maxsize=1)
def code_digest() -> str:
    """SHA-256 (hex) of every source and asset file of the packages that compute a run (:data:`CODE_PACKAGES`),
    by relative path and content: any edit to the code, a default included, changes it."""
    digest = hashlib.sha256()
    for package in CODE_PACKAGES:
        root = Path(sys.modules[package].__file__ if package in sys.modules else __import__(package).__file__).parent
        for path in sorted(p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                           and p.suffix not in (".pyc", ".pyo")):
            digest.update(f"{package}/{path.relative_to(root).as_posix()}".encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()


def _input_files(value: Any) -> list[str]:
    """Every string in a task (nested) that names an existing file: the task's input files."""
    if isinstance(value, dict):
        return [f for v in value.values() for f in _input_files(v)]
    if isinstance(value, list):
        return [f for v in value for f in _input_files(v)]
    if isinstance(value, str) and len(value) < 4096 and os.path.isfile(value):
        return [value]
    return []


def task_digest(task: dict) -> str:
    """SHA-256 (hex) of what a run's result depends on: the task's canonical JSON, :func:`code_digest` and the
    content (not the path) of every input file the task names."""
    files = {path: sha256(path) for path in sorted(set(_input_files(task)))}
    content = sorted(files.values())
    return hashlib.sha256(_canonical_json({"task": task, "code": code_digest(), "input_files": content})
                          .encode("utf-8")).hexdigest()


def _canonical_json(value: Any) -> str:
    """JSON text that is the same for equal values (sorted keys, fixed separators)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def _result_path(runs_dir: Path, key: str) -> Path:
    """Result file of the run ``key``."""
    return runs_dir / f"{key}.json"


def _load_stored(path: Path, digest: str) -> dict | None:
    """The stored result in ``path`` if it was computed from the task with ``digest``, else None."""
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return None
    except (ValueError, UnicodeDecodeError) as exc:
        logger.warning("%s is unreadable (%s); the run is recomputed", path, exc)
        return None
    is_current = isinstance(record, dict) and record.get("task_sha256") == digest
    if not is_current or not isinstance(record.get("result"), dict):
        logger.info("%s holds a result for another task; the run is recomputed", path)
        return None
    return record["result"]


def _store(path: Path, task: dict, digest: str, result_json: str) -> dict:
    """Write a run's result file atomically; return the result as read back from its JSON text."""
    record = {
        "format": RESULT_FORMAT, "key": task["key"], "task_sha256": digest, "task": task,
        "result": json.loads(result_json),
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(path, json.dumps(record) + "\n")
    return record["result"]


def _execute(fn: Callable[[dict], dict], task: dict) -> tuple[bool, str]:
    """Run one task wherever it is scheduled: (True, result as JSON text) or (False, traceback text)."""
    try:
        result = fn(task)
        if not isinstance(result, dict):
            raise TypeError(f"fn must return a dict, returned {type(result).__name__}: {result!r:.200}")
        return True, json.dumps(result)
    except Exception:
        return False, traceback.format_exc()


def _outcomes(fn, tasks, pending, workers, scheduler) -> Iterator[_Outcome]:
    """Outcomes of the pending tasks in finishing order, from the backend the arguments select."""
    if not pending:
        return
    if scheduler is not None:
        yield from _dask_outcomes(fn, tasks, pending, scheduler)
        return
    workers = (os.cpu_count() or 1) if workers is None else workers
    if workers == 1:
        for index in pending:
            yield index, *_execute(fn, tasks[index])
    else:
        yield from _pool_outcomes(fn, tasks, pending, min(workers, len(pending)))


def _start_method() -> str:
    """``"forkserver"`` where available, else ``"spawn"``: never fork a parent holding numba/MuJoCo state."""
    return "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"


def _pool_outcomes(fn, tasks, pending, workers) -> Iterator[_Outcome]:
    """Run the pending tasks on a local process pool."""
    try:
        pickle.dumps(fn)
    except Exception as exc:
        raise TypeError(
            f"fn {fn!r} cannot be pickled for the worker processes ({exc}); define it at the top level of an "
            "importable module, or pass workers=1 to run in this process"
        ) from exc
    with process_pool(workers) as pool:
        futures = {pool.submit(_execute, fn, tasks[index]): index for index in pending}
        try:
            for future in concurrent.futures.as_completed(futures):
                yield futures[future], *_future_outcome(future)
        finally:
            pool.shutdown(wait=False, cancel_futures=True)


def process_pool(workers: int) -> concurrent.futures.ProcessPoolExecutor:
    """A local pool of ``workers`` processes under the runner's rules: never forked from a parent holding numba or
    MuJoCo state, one numba and one BLAS thread each, none outliving the process that started it. The navigation
    filter is compiled here first (:func:`nav.ekf.compile_filter`; loaded from numba's cache when it is there), so
    that the workers load it rather than each compiling it at once."""
    from nav.ekf import compile_filter  # here: importing the runner alone does not load numba

    compile_filter()
    return concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context(
        _start_method()), initializer=_start_worker, initargs=(os.getpid(),))


def _start_worker(parent_pid: int) -> None:
    """Worker initializer: one numba and one BLAS thread (:func:`limit_worker_threads`), freed memory kept for
    reuse (:func:`keep_freed_memory`) and no life beyond the parent's."""
    limit_worker_threads()
    keep_freed_memory()
    _die_with_parent(parent_pid)


MMAP_THRESHOLD_BYTES = 32 * 2**20  # glibc's largest: blocks up to this size come from the heap
TRIM_THRESHOLD_BYTES = 256 * 2**20  # free memory at the top of the heap kept before any goes back to the kernel


def keep_freed_memory() -> None:
    """Have glibc's malloc serve blocks of up to :data:`MMAP_THRESHOLD_BYTES` from its heap and keep up to
    :data:`TRIM_THRESHOLD_BYTES` of freed memory there, for a worker that runs task after task.

    A walk allocates and frees arrays of its 84,000 samples (1 to 20 MB each) hundreds of times; every block
    mapped afresh from the kernel is paid again in page faults when first written (about a sixth of the truth's
    CPU time). Dask's nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which also pins the mmap
    threshold at 128 kB, so there every such array is mapped anew. Memory only, no numbers change. Nothing
    happens where the C library is not glibc.
    """
    try:
        libc = ctypes.CDLL("libc.so.6")
    except OSError:
        return
    m_trim_threshold, m_mmap_threshold = -1, -3  # mallopt parameters (malloc.h)
    libc.mallopt(m_mmap_threshold, MMAP_THRESHOLD_BYTES)
    libc.mallopt(m_trim_threshold, TRIM_THRESHOLD_BYTES)


def limit_worker_threads() -> None:
    """Run numba and BLAS/OpenMP code on one thread each: a worker of a pool or cluster that parallelises over
    tasks. The BLAS limit holds for the whole process, numba's for the calling thread (numba keeps the count per
    thread), so a Dask worker calls this in the thread that runs each task. Results do not depend on it
    (tests/test_runner.py compares one and two BLAS threads).

    The counts are set at run time rather than through ``NUMBA_NUM_THREADS`` or ``OPENBLAS_NUM_THREADS``: numba
    refuses a changed variable once its threads are up, so setting it in a process that has already compiled (a
    test session, a notebook) breaks that process's next compilation, and BLAS reads its variable only when it
    loads, which in a forkserver worker has already happened.
    """
    import numba
    from threadpoolctl import threadpool_limits

    numba.set_num_threads(1)
    threadpool_limits(1)


def _die_with_parent(parent_pid: int) -> None:
    """Worker initializer: end this worker when the process that started the pool is gone.

    On Linux the kernel sends SIGKILL when the worker's own parent (the forkserver) exits; a daemon thread polls
    ``parent_pid`` as well, which also covers platforms without that and a forkserver that outlives the run.
    """
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            import signal

            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG = 1
        except (OSError, AttributeError):
            pass

    def watch() -> None:
        while True:
            time.sleep(WATCHDOG_INTERVAL_S)
            try:
                os.kill(parent_pid, 0)
            except ProcessLookupError:
                os._exit(1)
            except PermissionError:  # the pid belongs to someone else now: the parent is gone
                os._exit(1)

    threading.Thread(target=watch, name="die-with-parent", daemon=True).start()


def _dask_outcomes(fn, tasks, pending, scheduler) -> Iterator[_Outcome]:
    """Run the pending tasks on a Dask cluster given by address or by a connected Client."""
    try:
        import distributed
    except ImportError as exc:
        raise ImportError(
            "running on a Dask cluster (scheduler=...) needs the optional 'distributed' package: "
            "pip install gaitsim[dask]"
        ) from exc
    own_client = isinstance(scheduler, str)
    if own_client:
        try:
            client = distributed.Client(scheduler)
        except OSError as exc:
            raise RuntimeError(f"cannot connect to the Dask scheduler at {scheduler!r}: {exc}") from exc
    else:
        client = scheduler
    futures = {}
    try:
        futures = {client.submit(_execute_on_cluster, fn, tasks[index], pure=False): index for index in pending}
        for future in distributed.as_completed(list(futures)):
            yield futures[future], *_future_outcome(future)
    finally:
        unfinished = [future for future in futures if not future.done()]
        if unfinished:
            client.cancel(unfinished)
        if own_client:
            client.close()


def _execute_on_cluster(fn: Callable[[dict], dict], task: dict) -> tuple[bool, str]:
    """:func:`_execute` on a Dask worker, in the worker's task thread under :func:`limit_worker_threads` (about
    2 ms per task) and :func:`keep_freed_memory`."""
    limit_worker_threads()
    keep_freed_memory()
    return _execute(fn, task)


def _future_outcome(future) -> tuple[bool, str]:
    """What ``_execute`` returned, or the traceback of a failure outside ``fn`` (e.g. a dead worker)."""
    try:
        return future.result()
    except Exception as exc:
        return False, "".join(traceback.format_exception(exc))


def _failure_message(failures: dict[str, str], n_tasks: int, runs_dir: Path) -> str:
    """Error text: how many runs failed, their keys, and the first traceback."""
    first_key, first_traceback = next(iter(failures.items()))
    return (
        f"{len(failures)} of {n_tasks} runs failed: {', '.join(failures)}. The other results are stored in "
        f"{runs_dir}; fix the cause and call again to compute only the missing runs.\n"
        f"First failure ({first_key}):\n{first_traceback}"
    )
