"""`gaitsim generate` in a fresh process loads only what it needs: not numba (the IMU model's numpy reference path
serves a short record; numba's first use costs ~0.65 s), not MuJoCo's OpenGL backend, not the experiment runner,
the filter or scipy.signal; and the recording it writes is the one the Python API writes."""

import json
import subprocess
import sys
from pathlib import Path

from gaitsim.scenario import load_scenario
from gaitsim.simulate import simulate_walk

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = """[scenario]
name = "short"
seed = 7

[path]
kind = "straight"
length_m = 4.0

[sampling]
rate_hz = 200.0

[sensor]
preset = "paper-vn200"
"""
NOT_LOADED = ("numba", "glfw", "scipy.signal", "gaitsim.experiments.runner", "nav.pipeline")
PROBE = """import json, sys
from gaitsim.cli import main
code = main(["generate", sys.argv[1], "--out", sys.argv[2], "--no-progress"])
print(json.dumps({"code": code, "loaded": [m for m in sys.argv[3:] if m in sys.modules]}))
"""


def test_generate_loads_no_numba_renderer_or_filter(tmp_path):
    scenario = tmp_path / "short.toml"
    scenario.write_text(SCENARIO)
    done = subprocess.run([sys.executable, "-c", PROBE, str(scenario), str(tmp_path / "rec"), *NOT_LOADED],
                          cwd=ROOT, capture_output=True, text=True, check=True)
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report == {"code": 0, "loaded": []}
    from nav.recording import read_recording

    written, simulated = read_recording(tmp_path / "rec"), simulate_walk(load_scenario(scenario))
    assert written.acc.tobytes() == simulated.acc.tobytes() and written.gyr.tobytes() == simulated.gyr.tobytes()
