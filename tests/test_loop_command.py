"""``gaitsim loop`` on a recording folder: attribution.json with the contract's fields, atomic output."""

import json

import pytest

from gaitsim.cli import main
from gaitsim.loop import blind
from nav.recording import write_recording


@pytest.fixture(scope="module")
def loop_output(tmp_path_factory):
    base = tmp_path_factory.mktemp("loop")
    rec = blind.blind_recording(blind.BY_NAME["accel_scale"])
    write_recording(rec, base / "rec")
    assert main(["loop", str(base / "rec"), "--out", str(base / "out"), "--rounds", "1"]) == 0
    return base


def test_attribution_json_names_effect_magnitude_and_before_after(loop_output):
    doc = json.loads((loop_output / "out" / "recording" / "attribution.json").read_text())
    first = doc["attributions"][0]
    assert first["effect"] == "accel_scale"
    assert first["magnitude_unit"] == "%"
    assert first["magnitude"] == pytest.approx(2.0, rel=0.25)
    assert abs(first["residual_after"]) < abs(first["residual_before"]) / 10
    assert 0.9 <= first["fraction_explained"] <= 1.0
    nav = doc["navigation"]["nav_final_error"]
    assert nav["discrepancy_after"] < nav["discrepancy_before"] / 3
    assert (loop_output / "out" / "recording" / "report.md").read_text().count("accel_scale") >= 1
    assert (loop_output / "out" / "recording" / "profiles.png").stat().st_size > 1000


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
