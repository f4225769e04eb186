"""``gaitsim loop`` on a recording folder without any reference: signatures only, twin.toml, atomic output."""

import json

import pytest

from gaitsim.cli import main
from gaitsim.loop import blind
from gaitsim.scenario import load_scenario
from nav.recording import Recording, write_recording


@pytest.fixture(scope="module")
def loop_output(tmp_path_factory):
    base = tmp_path_factory.mktemp("loop")
    rec = blind.blind_recording("paper-vn200", blind.BY_NAME["accel_scale_x"])
    write_recording(Recording(rec.t, rec.acc, rec.gyr, meta={}), base / "rec")  # imu alone
    assert main(["loop", str(base / "rec"), "--out", str(base / "out"), "--max-effects", "1"]) == 0
    return base


def test_a_recording_without_reference_gets_signature_residuals_and_says_why_navigation_is_absent(loop_output):
    doc = json.loads((loop_output / "out" / "recording" / "attribution.json").read_text())
    assert doc["reference"]["kind"] == "none"
    assert doc["navigation"] == {}
    assert "no reference" in (loop_output / "out" / "recording" / "report.md").read_text()
    assert not any(name.startswith("nav_") for name in doc["residuals_before"])
    # the injected accelerometer x scale shows in the stride closure
    assert doc["residuals_before"]["closure_forward"]["z"] > 3


def test_the_fitted_twin_is_a_scenario_file_that_generate_reads(loop_output):
    twin = load_scenario(loop_output / "out" / "recording" / "twin.toml")
    doc = json.loads((loop_output / "out" / "recording" / "attribution.json").read_text())
    assert twin.rate_hz == pytest.approx(doc["twin_after"]["scenario"]["sampling"]["rate_hz"])
    assert twin.walk.gait.cadence_steps_per_min == pytest.approx(
        doc["twin_after"]["scenario"]["gait"]["cadence_steps_per_min"], rel=1e-6)


def test_existing_output_is_refused_and_left_alone(loop_output, capsys):
    before = (loop_output / "out" / "README.md").read_text()
    code = main(["loop", str(loop_output / "rec"), "--out", str(loop_output / "out")])
    assert code == 2 and "exists" in capsys.readouterr().err
    assert (loop_output / "out" / "README.md").read_text() == before


def test_unknown_dataset_is_an_error_naming_the_choices(tmp_path, capsys):
    code = main(["loop", "no-such-dataset", "--out", str(tmp_path / "x")])
    assert code == 2
    err = capsys.readouterr().err
    assert "gaitmap-healthy" in err and "no-such-dataset" in err
    assert not (tmp_path / "x").exists()
