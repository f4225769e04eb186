"""Experiment runner: identical results across backends, resume, recomputation of changed tasks, failures."""

import json
import platform
import re
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from gaitsim.errors import ScenarioError
from gaitsim.experiments.runner import RunsFailedError, derive_seed, run_tasks


def random_walk_end(task: dict) -> dict:
    """A small deterministic run: a seeded random walk and some arithmetic on it.

    Optional task fields steer the test harness: ``marker_dir`` (one file per call is created there, to count
    calls), ``fail`` (raise), ``delay_s`` (sleep first, to shuffle the finishing order).
    """
    if "marker_dir" in task:
        name = task["key"].replace("/", "__")
        (Path(task["marker_dir"]) / f"{name}.{uuid.uuid4().hex}").touch()
    time.sleep(task.get("delay_s", 0.0))
    if task.get("fail"):
        raise ValueError(f"deliberate failure in {task['key']}")
    if task.get("interrupt"):
        raise KeyboardInterrupt
    rng = np.random.default_rng(task["seed"])
    steps = rng.normal(0.0, task["sigma"], size=(task["n_steps"], 2))
    track = np.cumsum(steps, axis=0)
    return {
        "end": track[-1].tolist(),
        "path_length": float(np.sum(np.hypot(steps[:, 0], steps[:, 1]))),
        "max_distance": float(np.max(np.hypot(track[:, 0], track[:, 1]))),
    }


def make_tasks(n: int, **extra) -> list[dict]:
    """Tasks of two variants, seeded with derive_seed, keys with sub-folders."""
    tasks = []
    for i in range(n):
        variant = "before" if i % 2 == 0 else "after"
        tasks.append({
            "key": f"{variant}/run-{i:03d}", "seed": derive_seed(2024, variant, i),
            "sigma": 0.1 + 0.01 * i, "n_steps": 500, **extra,
        })
    return tasks


def calls_per_key(marker_dir: Path) -> dict[str, int]:
    """How many times each key was computed, from the marker files."""
    counts: dict[str, int] = {}
    for marker in marker_dir.iterdir():
        key = marker.name.rsplit(".", 1)[0].replace("__", "/")
        counts[key] = counts.get(key, 0) + 1
    return counts


def expected(task: dict) -> dict:
    """The run computed in this process, JSON round trip included."""
    return json.loads(json.dumps(random_walk_end(task)))


def test_serial_and_pool_give_identical_results_in_task_order(tmp_path):
    # later tasks finish first on the pool: the returned order must still be the task order
    tasks = make_tasks(6)
    for position, task in enumerate(tasks):
        task["delay_s"] = 0.03 * (len(tasks) - position)
    serial = run_tasks(random_walk_end, tasks, tmp_path / "serial", workers=1, progress=False)
    pooled = run_tasks(random_walk_end, tasks, tmp_path / "pool", workers=2, progress=False)
    assert serial == pooled == [expected(task) for task in tasks]
    assert len({tuple(result["end"]) for result in serial}) == len(tasks)  # seeds differ per run


def test_stored_files_hold_the_returned_results(tmp_path):
    tasks = make_tasks(3)
    results = run_tasks(random_walk_end, tasks, tmp_path, workers=1, progress=False)
    for task, result in zip(tasks, results):
        record = json.loads((tmp_path / "runs" / f"{task['key']}.json").read_text())
        assert record["key"] == task["key"] and record["task"] == task
        assert record["result"] == result


def test_resume_recomputes_only_the_missing_result(tmp_path):
    markers = tmp_path / "markers"
    markers.mkdir()
    tasks = make_tasks(5, marker_dir=str(markers))
    first = run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=2, progress=False)
    assert calls_per_key(markers) == {task["key"]: 1 for task in tasks}
    (tmp_path / "exp" / "runs" / "after" / "run-003.json").unlink()
    second = run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=2, progress=False)
    counts = calls_per_key(markers)
    assert counts.pop("after/run-003") == 2
    assert set(counts.values()) == {1}
    assert second == first
    third = run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=2, progress=False)  # nothing to do
    assert calls_per_key(markers) == {**counts, "after/run-003": 2}
    assert third == first


def test_unreadable_result_file_is_recomputed(tmp_path):
    tasks = make_tasks(2)
    first = run_tasks(random_walk_end, tasks, tmp_path, workers=1, progress=False)
    result_file = tmp_path / "runs" / "after" / "run-001.json"
    result_file.write_text(result_file.read_text()[:40])  # e.g. written by hand and cut short
    assert run_tasks(random_walk_end, tasks, tmp_path, workers=1, progress=False) == first
    assert json.loads(result_file.read_text())["result"] == first[1]


def test_interrupted_experiment_resumes_where_it_stopped(tmp_path):
    markers = tmp_path / "markers"
    markers.mkdir()
    tasks = make_tasks(5, marker_dir=str(markers))
    tasks[3]["interrupt"] = True
    with pytest.raises(KeyboardInterrupt):
        run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=1, progress=False)
    stored = sorted(path.relative_to(tmp_path / "exp" / "runs").as_posix()
                    for path in (tmp_path / "exp" / "runs").rglob("*.json"))
    assert stored == sorted(f"{task['key']}.json" for task in tasks[:3])
    del tasks[3]["interrupt"]  # the task itself changed: it is rerun along with the one never started
    results = run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=1, progress=False)
    assert calls_per_key(markers) == {task["key"]: 2 if i == 3 else 1 for i, task in enumerate(tasks)}
    assert results == [expected(task) for task in tasks]


def test_changed_task_is_recomputed(tmp_path):
    markers = tmp_path / "markers"
    markers.mkdir()
    tasks = make_tasks(4, marker_dir=str(markers))
    first = run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=1, progress=False)
    tasks[2] = {**tasks[2], "sigma": 2 * tasks[2]["sigma"]}  # same key and seed, doubled step size
    second = run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=1, progress=False)
    counts = calls_per_key(markers)
    assert counts.pop(tasks[2]["key"]) == 2 and set(counts.values()) == {1}
    # same seed, doubled sigma: the walk scales by exactly 2
    assert np.allclose(second[2]["end"], 2 * np.asarray(first[2]["end"]), rtol=1e-12)
    assert second[:2] == first[:2] and second[3] == first[3]


def test_failed_task_is_named_and_the_others_are_stored(tmp_path, caplog):
    tasks = make_tasks(4)
    tasks[1]["fail"] = True
    with pytest.raises(RunsFailedError) as caught:
        run_tasks(random_walk_end, tasks, tmp_path, workers=2, progress=False)
    key = tasks[1]["key"]
    assert f"1 of 4 runs failed: {key}." in str(caught.value)
    assert isinstance(caught.value, RuntimeError)
    assert list(caught.value.failures) == [key]
    assert "ValueError: deliberate failure in after/run-001" in caught.value.failures[key]
    assert "in random_walk_end" in caught.value.failures[key]  # the worker's traceback, not just the message
    assert key in caplog.text and "deliberate failure" in caplog.text
    assert not (tmp_path / "runs" / f"{key}.json").exists()
    for task in tasks[:1] + tasks[2:]:
        stored = json.loads((tmp_path / "runs" / f"{task['key']}.json").read_text())["result"]
        assert stored == expected(task)
    # fixing the task and calling again completes the experiment
    tasks[1]["fail"] = False
    results = run_tasks(random_walk_end, tasks, tmp_path, workers=1, progress=False)
    assert results == [expected(task) for task in tasks]


def test_non_dict_result_is_a_failure_of_that_run(tmp_path):
    with pytest.raises(RunsFailedError) as caught:
        run_tasks(np.linalg.norm, [{"key": "a"}], tmp_path, workers=1, progress=False)
    assert "a" in caught.value.failures


@pytest.mark.parametrize(
    ("tasks", "message"),
    [
        ([{"key": "a"}, {"key": "a"}], "repeats key 'a'"),
        ([{"key": "Run-1"}, {"key": "run-1"}], "repeats key 'Run-1'"),
        ([{"key": "../escape"}], "key '../escape' is not allowed"),
        ([{"key": "/abs"}], "key '/abs' is not allowed"),
        ([{"seed": 3}], "task #0 must be a dict with a string 'key'"),
        ([{"key": "a", "x": {1, 2}}], "task 'a' is not JSON-serialisable"),
        ([{"key": "a.json/b"}, {"key": "a"}], "keys ['a'] end in '.json'"),
    ],
)
def test_bad_tasks_are_rejected_before_anything_is_written(tmp_path, tasks, message):
    with pytest.raises(ScenarioError) as caught:
        run_tasks(random_walk_end, tasks, tmp_path / "exp", workers=1, progress=False)
    assert message in str(caught.value)
    assert not (tmp_path / "exp").exists()


def test_bad_backend_arguments_are_rejected(tmp_path):
    with pytest.raises(ScenarioError, match="workers must be an int >= 1"):
        run_tasks(random_walk_end, make_tasks(1), tmp_path / "exp", workers=0, progress=False)
    with pytest.raises(ScenarioError, match="leave it unset with scheduler"):
        run_tasks(random_walk_end, make_tasks(1), tmp_path / "exp", workers=2, scheduler="tcp://x:1")
    with pytest.raises(ScenarioError, match="scheduler must be a Dask scheduler address"):
        run_tasks(random_walk_end, make_tasks(1), tmp_path / "exp", scheduler=8786)
    assert not (tmp_path / "exp").exists()


def test_missing_distributed_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # makes `import distributed` fail
    with pytest.raises(ImportError, match=re.escape("pip install gaitsim[dask]")):
        run_tasks(random_walk_end, make_tasks(2), tmp_path / "exp", scheduler="tcp://127.0.0.1:1", progress=False)
    assert not (tmp_path / "exp").exists()


def test_unpicklable_fn_is_refused_for_a_pool(tmp_path):
    with pytest.raises(TypeError, match="workers=1"):
        run_tasks(lambda task: {}, make_tasks(2), tmp_path, workers=2, progress=False)


PINNED_SEED_BEFORE_0 = 1619618868692896566  # derive_seed(2024, "before", 0), computed once


def test_derive_seed_is_pinned_and_separates_names():
    # pinned values: must not change across processes, platforms, Python and numpy versions
    assert derive_seed(2024, "before", 0) == PINNED_SEED_BEFORE_0
    assert derive_seed(0) == int(np.random.SeedSequence(0).generate_state(1, dtype=np.uint64)[0])
    seeds = {derive_seed(2024, "before", 0), derive_seed(2024, "before", "0"), derive_seed(2024, 0, "before"),
             derive_seed(2025, "before", 0), derive_seed(2024, "before", 1), derive_seed(2024, "before")}
    assert len(seeds) == 6
    with pytest.raises(ValueError, match="base_seed"):
        derive_seed(-1, "x")
    with pytest.raises(ValueError, match="names must be str or int"):
        derive_seed(1, 1.5)



def test_dask_cluster_matches_local_pool_and_serial(tmp_path):
    import distributed  # in the test extra on purpose: CI must run this test, not skip it
    markers = tmp_path / "markers"
    markers.mkdir()
    tasks = make_tasks(6, marker_dir=str(markers))
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        by_address = run_tasks(random_walk_end, tasks, tmp_path / "dask", scheduler=cluster.scheduler_address,
                               progress=False)
        # resume on the cluster with a connected Client: one missing result is recomputed, the others loaded
        (tmp_path / "dask" / "runs" / "before" / "run-002.json").unlink()
        with distributed.Client(cluster) as client:
            resumed = run_tasks(random_walk_end, tasks, tmp_path / "dask", scheduler=client, progress=False)
    counts = calls_per_key(markers)
    assert counts.pop("before/run-002") == 2 and set(counts.values()) == {1}
    serial = run_tasks(random_walk_end, tasks, tmp_path / "serial", workers=1, progress=False)
    pooled = run_tasks(random_walk_end, tasks, tmp_path / "pool", workers=2, progress=False)
    assert by_address == resumed == pooled == serial == [expected(task) for task in tasks]


def test_a_runs_numbers_do_not_depend_on_the_blas_thread_count():
    # limit_worker_threads gives pool and Dask workers one BLAS thread while a serial run keeps the caller's: the
    # IMU model, the compensation (solve), the filter and the scores must come out identical either way
    from nav_synthetic import synthetic_walk
    from threadpoolctl import threadpool_limits

    from gaitsim.imu.model import apply_sensor
    from gaitsim.imu.presets import get_preset
    from nav import pipeline
    from nav.recording import Recording

    walk = synthetic_walk(strides=4)
    sensor = get_preset("paper-vn200")
    options = pipeline.NavOptions(calibration=sensor.deterministic(), rts=True)

    def navigate(threads):
        with threadpool_limits(threads):
            t, acc, gyr = apply_sensor(sensor, walk.t, walk.truth.acc, walk.truth.gyr, np.random.default_rng(5))
            sol, score = pipeline.run(Recording(t=t, acc=acc, gyr=gyr, truth=walk.truth), options)
        return acc, gyr, sol.pos, sol.quat, json.dumps(score, sort_keys=True, default=str)

    one, two = navigate(1), navigate(2)
    for a, b in zip(one[:4], two[:4]):
        np.testing.assert_array_equal(a, b)
    assert one[4] == two[4]


FREED_KEPT = """
import ctypes, sys
import numpy as np
class MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks", "keepcost")]
libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = MallInfo2
if sys.argv[1] == "keep":
    from gaitsim.experiments.runner import keep_freed_memory
    keep_freed_memory()
block = np.ones(2_000_000)  # 16 MB
del block
print(libc.mallinfo2().fordblks)
"""


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="keep_freed_memory sets glibc's malloc")
def test_workers_keep_a_walks_freed_arrays_for_reuse():
    # a fresh process frees a 16 MB array back to the kernel (mapped on its own); a worker keeps it in its heap
    def free_bytes_kept(mode):
        run = subprocess.run([sys.executable, "-c", FREED_KEPT, mode], capture_output=True, text=True, check=True,
                             cwd=Path(__file__).resolve().parents[1])
        return int(run.stdout)

    assert free_bytes_kept("plain") < 2**20
    assert free_bytes_kept("keep") >= 16_000_000
