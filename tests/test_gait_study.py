"""The gait study (issue 17): the committed results/gaits still follow from the code, its inputs are checked."""

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from gaitsim.errors import ScenarioError
from gaitsim.experiments.gait_study import parse_gaits
from gaitsim.experiments.tasks import walk_task

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results" / "gaits"


def test_a_committed_run_of_the_study_still_matches():
    """Recompute the shortest committed run (one gait, both pipelines) from its stored task and inputs."""
    study = json.loads((RESULTS / "gait_study.json").read_text())
    durations = [score["walk"]["duration_s"] for score in study["scores"]]
    i = int(np.argmin(durations))
    task = copy.deepcopy(study["tasks"][i])
    for variant in task["variants"]:
        for key in ("calibration", "stance_velocity"):
            if key in variant:
                variant[key] = str(RESULTS / variant[key])
    again = walk_task(task)
    for name, stored in study["scores"][i]["variants"].items():
        for metric in ("length_ratio", "heading_drift_deg_per_s", "final_error_m"):
            assert again["variants"][name][metric] == pytest.approx(stored[metric], rel=1e-6, abs=1e-9), (name, metric)


def test_running_is_in_the_study_and_summarised_per_pipeline():
    study = json.loads((RESULTS / "gait_study.json").read_text())
    assert any(label.startswith("run-forefoot") for label in study["summary"])
    for pipes in study["summary"].values():
        assert set(pipes) == {"before", "both"}
        assert pipes["before"]["runs"] == pipes["both"]["runs"] == study["runs"]


@pytest.mark.parametrize("value, fragment", [
    ([], "must be a non-empty list"), (["walk"], "'walk' is not allowed"), (["jog@100"], "'jog@100' is not allowed"),
    (["custom@84"], "'custom@84' is not allowed")])
def test_bad_gait_lists_are_refused_by_entry(value, fragment):
    with pytest.raises(ScenarioError, match="study.toml") as err:
        parse_gaits(value, "study.toml [experiment]")
    assert fragment in str(err.value)
