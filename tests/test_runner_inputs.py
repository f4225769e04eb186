"""The runner's cache key (code and input-file content), dying workers, stale temporaries; the range table."""

import math
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gaitsim.experiments.runner import run_tasks
from gaitsim.ranges import RANGES, ranges_markdown
from gaitsim.scenario import WORLD_SECTIONS, scenario_keys
from gaitsim.world.gait import GaitParams
from nav.files import atomic_output_dir, remove_stale_temporaries

ROOT = Path(__file__).resolve().parents[1]
PROBE = """
import time


def creep(task):
    from gaitsim.world.gait import MicroMotionParams
    return {"creep_mps": MicroMotionParams().creep_velocity_mps[0]}


def sleepy(task):
    time.sleep(60)
    return {}
"""
RUN = ("import sys, json, probe; from gaitsim.experiments.runner import run_tasks; "
       "print(json.dumps(run_tasks(getattr(probe, sys.argv[1]), [{'key': 'a'}, {'key': 'b'}], sys.argv[2], "
       "workers=int(sys.argv[3]), progress=False)))")


def _copy_packages(folder: Path) -> None:
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc")
    for package in ("gaitsim", "nav"):
        shutil.copytree(ROOT / package, folder / package, ignore=ignore)
    (folder / "probe.py").write_text(PROBE)


def _run(folder: Path, fn: str, out: Path, workers: int = 1) -> str:
    env = {**os.environ, "PYTHONPATH": str(folder)}
    done = subprocess.run([sys.executable, "-c", RUN, fn, str(out), str(workers)], cwd=folder, env=env,
                          capture_output=True, text=True, check=True)
    return done.stdout


def test_a_changed_default_in_the_code_recomputes_and_the_rerun_differs(tmp_path):
    _copy_packages(tmp_path)
    out = tmp_path / "experiment"
    first = _run(tmp_path, "creep", out)
    assert _run(tmp_path, "creep", out) == first  # unchanged code: the stored runs are reused
    gait = tmp_path / "gaitsim" / "world" / "gait.py"
    text = gait.read_text()
    old = "creep_velocity_mps: tuple[float, float, float] = (0.0, 0.0, 0.0)"
    assert old in text
    gait.write_text(text.replace(old, old.replace("(0.0,", "(0.03,")))
    second = _run(tmp_path, "creep", out)
    assert '"creep_mps": 0.0' in first and '"creep_mps": 0.03' in second


def read_file(task):
    return {"text": Path(task["input"]).read_text()}


def test_an_input_file_counts_by_content(tmp_path):
    calibration = tmp_path / "calibration.json"
    calibration.write_text("one")
    tasks = [{"key": "a", "input": str(calibration)}]
    assert run_tasks(read_file, tasks, tmp_path / "out", workers=1, progress=False) == [{"text": "one"}]
    calibration.write_text("two")  # same path, new content
    assert run_tasks(read_file, tasks, tmp_path / "out", workers=1, progress=False) == [{"text": "two"}]


def _descendants(pid: int) -> set[int]:
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            parents[int(entry.name)] = int(fields[1])
    found, frontier = set(), {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the process tree from /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_killing_a_pool_run_leaves_no_process_behind(tmp_path, sig):
    (tmp_path / "probe.py").write_text(PROBE)
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{ROOT}"}
    parent = subprocess.Popen([sys.executable, "-c", RUN, "sleepy", str(tmp_path / "out"), "2"], cwd=tmp_path,
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    children: set[int] = set()
    while time.monotonic() < deadline and len(children) < 3:  # forkserver and two workers (+ resource tracker)
        time.sleep(0.2)
        children = _descendants(parent.pid)
    assert len(children) >= 3, "the pool never started"
    parent.send_signal(sig)
    parent.wait()
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and any(_alive(pid) for pid in children):
        time.sleep(0.2)
    assert not [pid for pid in children if _alive(pid)]


def test_stale_temporaries_of_dead_writers_are_removed_on_the_next_start(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    pid = int(dead.stdout)
    stale_dir = tmp_path / f".out.tmp-{pid}-abcd"
    stale_dir.mkdir()
    (stale_dir / "imu.csv").write_text("half")
    stale_file = tmp_path / f".score.json.{pid}.xyz.tmp"
    stale_file.write_text("half")
    mine = tmp_path / f".other.tmp-{os.getpid()}-live"
    mine.mkdir()
    with atomic_output_dir(tmp_path / "out") as tmp:
        (tmp / "a.txt").write_text("done")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["out", mine.name])
    assert remove_stale_temporaries(tmp_path) == []


def test_every_numeric_world_key_has_a_range_and_the_docs_table_is_the_code():
    for section, cls in WORLD_SECTIONS.items():
        defaults = cls()
        for key, name in scenario_keys(cls).items():
            value = getattr(defaults, name)
            if isinstance(value, (int, float, tuple)) and not isinstance(value, bool):
                assert key in RANGES[section], f"[{section}] {key} has no range in gaitsim/ranges.py"
    assert (ROOT / "docs" / "scenario-ranges.md").read_text() == ranges_markdown()


def test_the_key_reference_gives_each_key_its_unit_default_and_range():
    rows = {line.split("|")[1].strip(" `"): [c.strip() for c in line.split("|")[2:-1]]
            for line in ranges_markdown().splitlines() if line.startswith("| `")}
    assert rows["rate_hz"] == ["Hz", "800", "[50, 5000]", RANGES["sampling"]["rate_hz"].source]
    assert rows["length_m"][:3] == ["m", "required", "(0, 100000]"]
    assert rows["pitch_toe_off_deg"][:2] == ["deg", f"{math.degrees(GaitParams().pitch_toe_off):g}"]
    assert rows["gyro_range"][:2] == ["rad/s", "inf"] and "deg/s" in rows["gyro_range"][2]
    assert all(key in rows for table in RANGES.values() for key in table)
