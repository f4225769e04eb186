"""Scenario validation (every documented error, nothing written) and recording round trips."""

from pathlib import Path

import numpy as np
import pytest

from gaitsim.cli import main
from gaitsim.errors import ScenarioError
from gaitsim.experiments.setup import targets_from_scenario
from gaitsim.scenario import load_scenario, scenario_document, scenario_from_dict, with_changes
from gaitsim.simulate import generate
from gaitsim.world import path as paths
from nav import storage
from nav.recording import IMU_COLUMNS, TRUTH_COLUMNS, TRUTH_RESOLUTION, RecordingError, read_recording

ROOT = Path(__file__).resolve().parents[1]

GOOD = """
[scenario]
name = "tiny"
seed = 3
[path]
kind = "straight"
length_m = 4.2
yaw_deg = 45.0
[gait]
stand_start_s = 0.6
stand_end_s = 0.6
[sampling]
rate_hz = 200.0
"""

BAD = {
    "unknown key": ('[gait]\ncadense_steps_per_min = 90.0', "unknown key 'cadense_steps_per_min'"),
    "unknown section": ('[gate]\ncadence_steps_per_min = 90.0', "unknown section [gate]"),
    "wrong type": ('[gait]\ncadence_steps_per_min = "fast"', "must be a number"),
    "zero cadence": ("[gait]\ncadence_steps_per_min = 0.0", "cadence_steps_per_min = 0.0"),
    "negative length": ('[path]\nkind = "straight"\nlength_m = -5.0', "length_m = -5.0"),
    "phase sum": ("[gait]\nswing_frac = 0.5", "must add up to 1"),
    "tight turn": ('[path]\nkind = "arc"\nradius_m = 0.3\nturn_deg = 90.0', "radius_m = 0.3"),
    "tight corner": ('[path]\nkind = "polyline"\nwaypoints_m = [[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]]\ncorner_radius_m = 0.2',
                     "corner_radius_m = 0.2"),
    "unknown path kind": ('[path]\nkind = "spiral"', "kind = 'spiral'"),
    "bad mount": ('[mount]\nsite = "ankle"', "site = 'ankle'"),
    "bad vector": ("[micromotion]\ncreep_velocity_mps = [0.01, 0.0]", "list of 3 numbers"),
    "low rate": ("[sampling]\nrate_hz = 10.0", "rate_hz = 10.0"),
    "slap too long": ("[impact]\nslap_duration_s = 0.5", "slap_duration_s = 0.5"),
    "negative seed": ("[scenario]\nseed = -1", "seed = -1"),
    "toes down at heel strike": ("[gait]\npitch_heel_strike_deg = 5.0", "pitch_heel_strike_deg = 5.0"),
}


def _merge(base: str, patch: str) -> str:
    """Replace the sections of ``base`` that ``patch`` defines."""
    import tomllib

    doc = tomllib.loads(base)
    new = tomllib.loads(patch)
    for k, v in new.items():
        if k == "path" or k not in doc:
            doc[k] = v
        else:
            doc[k].update(v)
    out = []
    for section, table in doc.items():
        out.append(f"[{section}]")
        for key, value in table.items():
            out.append(f"{key} = {_toml(value)}")
    return "\n".join(out) + "\n"


def _toml(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return repr(v)


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_scenario_is_refused_naming_the_key_and_writes_nothing(case, tmp_path, capsys):
    patch, message = BAD[case]
    f = tmp_path / "bad.toml"
    f.write_text(_merge(GOOD, patch))
    with pytest.raises(ScenarioError, match=None) as info:
        load_scenario(f)
    assert message in str(info.value) and str(f) in str(info.value)
    out = tmp_path / "out"
    assert main(["generate", str(f), "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists() and not any(p.name.startswith(".out") for p in tmp_path.iterdir())


def test_good_scenario_loads_with_units():
    f = load_scenario(ROOT / "scenarios/straight_100m.toml")
    assert f.walk.path.length == pytest.approx(99.6)
    assert f.rate_hz == 800.0 and f.walk.gait.cadence_steps_per_min == 84.0


def _assert_same_recording(back, rec):
    """Exact columns equal bit for bit; the truth's rounded columns within half their stored resolution."""
    np.testing.assert_array_equal(back.t, rec.t)
    np.testing.assert_array_equal(back.acc, rec.acc)
    np.testing.assert_array_equal(back.gyr, rec.gyr)
    for name in ("t", "gyr", "acc", "dv", "dth", "stance"):
        np.testing.assert_array_equal(getattr(back.truth, name), getattr(rec.truth, name))
    for name, key in (("pos", "pos"), ("vel", "vel"), ("quat", "q")):
        half = 0.5 * 10.0 ** -TRUTH_RESOLUTION[key]
        assert np.max(np.abs(getattr(back.truth, name) - getattr(rec.truth, name))) <= half * (1 + 1e-6)
    np.testing.assert_array_equal(back.events.as_table(), rec.events.as_table())
    assert back.meta["seed"] == 3 and back.meta["gait"]["stride_length_m"] == 1.4


@pytest.mark.parametrize("form", ["csv.gz", "csv"])
def test_round_trip_in_each_form(form, tmp_path):
    scen = scenario_from_dict(__import__("tomllib").loads(GOOD), "tiny")
    (rec,) = generate(scen, tmp_path / "rec", form=form)
    names = sorted(p.name for p in (tmp_path / "rec").iterdir())
    assert names == sorted([f"events.{form}", f"imu.{form}", "meta.json", f"truth.{form}"])  # no binary duplicate
    back = read_recording(tmp_path / "rec")
    _assert_same_recording(back, rec)
    with storage.open_text(tmp_path / f"rec/truth.{form}") as fh:
        assert fh.readline().strip() == ",".join(TRUTH_COLUMNS)
    recorded = back.meta["storage"]["sha256"]
    assert recorded == {name: storage.sha256(tmp_path / "rec" / name) for name in names if name != "meta.json"}
    (again,) = generate(scen, tmp_path / "again", form=form)  # deterministic bytes (gzip without a timestamp)
    assert read_recording(tmp_path / "again").meta["storage"]["sha256"] == recorded


def test_parquet_twin_is_read_only_while_it_matches_its_csv(tmp_path):
    pytest.importorskip("pyarrow")
    scen = scenario_from_dict(__import__("tomllib").loads(GOOD), "tiny")
    (rec,) = generate(scen, tmp_path / "rec", parquet=True)
    assert (tmp_path / "rec/truth.parquet").exists()
    _assert_same_recording(read_recording(tmp_path / "rec"), rec)
    np.testing.assert_array_equal(read_recording(tmp_path / "rec").truth.as_table(),
                                  read_recording(tmp_path / "rec", prefer_binary=False).truth.as_table())
    # a CSV edited after the twin was written: the twin no longer matches and is ignored, loudly
    imu = tmp_path / "rec/imu.csv.gz"
    storage.write_text(imu, storage.table_text(IMU_COLUMNS, np.column_stack([rec.t, rec.acc + 1.0, rec.gyr])))
    with pytest.warns(UserWarning, match="does not carry the current digest of imu.csv.gz"):
        back = read_recording(tmp_path / "rec")
    np.testing.assert_array_equal(back.acc, rec.acc + 1.0)


def test_a_folder_with_both_a_csv_and_its_compressed_form_is_refused(tmp_path):
    scen = scenario_from_dict(__import__("tomllib").loads(GOOD), "tiny")
    generate(scen, tmp_path / "rec")
    (tmp_path / "rec/imu.csv").write_text(",".join(IMU_COLUMNS) + "\n")
    with pytest.raises(RecordingError, match="both imu.csv.gz and imu.csv"):
        read_recording(tmp_path / "rec")


def test_multi_run_output_and_refusal_to_clobber(tmp_path):
    scen = scenario_from_dict(__import__("tomllib").loads(GOOD), "tiny")
    recs = generate(scen, tmp_path / "many", runs=3)
    assert sorted(p.name for p in (tmp_path / "many").iterdir()) == ["run-000", "run-001", "run-002"]
    assert not np.array_equal(recs[0].events.t_ic, recs[1].events.t_ic)  # runs differ in stride variability
    with pytest.raises(FileExistsError):
        generate(scen, tmp_path / "many", runs=1)
    assert len(list((tmp_path / "many").iterdir())) == 3


def test_interrupted_generation_leaves_nothing(tmp_path, monkeypatch):
    import gaitsim.simulate as gen

    scen = scenario_from_dict(__import__("tomllib").loads(GOOD), "tiny")

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(gen, "write_recording_into", boom)
    with pytest.raises(KeyboardInterrupt):
        gen.generate(scen, tmp_path / "rec")
    assert list(tmp_path.iterdir()) == []


def test_degree_keys_are_held_in_si_and_written_back_in_degrees():
    doc = {"path": {"kind": "straight", "length_m": 5.0}, "gait": {"pitch_toe_off_deg": 50.0, "swing_roll_deg": 4.0},
           "impact": {"slap_rate_dps": 300.0}, "micromotion": {"stance_rotation_dps": [1.0, -2.0, 3.0]},
           "mount": {"rpy_deg": [10.0, -5.0, 2.0]}, "sensor": {"preset": "vn200", "withhold": True}}
    scen = scenario_from_dict(doc, "deg")
    assert scen.walk.gait.pitch_toe_off == pytest.approx(np.radians(50.0), rel=1e-15)
    assert scen.walk.impact.slap_rate == pytest.approx(np.radians(300.0), rel=1e-15)
    np.testing.assert_allclose(scen.walk.micro.stance_rotation_rate, np.radians([1.0, -2.0, 3.0]), rtol=1e-15)
    np.testing.assert_allclose(scen.mount.rpy, np.radians([10.0, -5.0, 2.0]), rtol=1e-15)
    written = scenario_document(scen)
    assert written["gait"]["pitch_toe_off_deg"] == 50.0 and written["impact"]["slap_rate_dps"] == 300.0
    assert written["micromotion"]["stance_rotation_dps"] == [1.0, -2.0, 3.0]
    again = scenario_from_dict(written, "written")
    assert again.walk == scen.walk and again.mount == scen.mount and again.rate_hz == scen.rate_hz
    for key in ("accel_noise_density", "gyro_bias_instability", "accel_misalignment"):
        np.testing.assert_allclose(again.sensor[key], scen.sensor[key], rtol=1e-15, atol=0)
    assert again.sensor.withheld


def test_changes_are_converted_and_validated_like_a_file():
    scen = scenario_from_dict(__import__("tomllib").loads(GOOD), "tiny")
    changed = with_changes(scen, {"gait": {"pitch_toe_off_deg": 40.0}, "sensor": {"accel_range": [4.0, "g"]}})
    assert changed.walk.gait.pitch_toe_off == pytest.approx(np.radians(40.0), rel=1e-15)
    assert float(changed.sensor["accel_range"]) == pytest.approx(4 * 9.80665)
    assert scen.walk.gait.pitch_toe_off == pytest.approx(np.radians(45.0), rel=1e-15)  # the original is unchanged
    with pytest.raises(ScenarioError, match="pitch_toe_off_deg = -3.0"):
        with_changes(scen, {"gait": {"pitch_toe_off_deg": -3.0}})
    with pytest.raises(ScenarioError, match="length"):
        with_changes(scen, {"gait": {"stride_length_m": 6.0}})  # longer than the 4.2 m path
    with pytest.raises(ScenarioError, match="cannot be changed"):
        with_changes(scen, {"path": {"length_m": 9.0}})


def test_rounded_corners_fit_exactly_when_the_tangent_cut_fits_the_legs():
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])  # a 90 deg corner cuts r tan(45 deg) = r per leg
    assert paths.corners_fit(square, 2.0) and not paths.corners_fit(square, 2.01)
    assert not paths.corners_fit(np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]]), 0.1)  # repeated waypoint
    with pytest.raises(ValueError):
        paths.polyline(square, 2.01)


def test_paper_targets_are_read_from_the_scenario_and_all_required():
    paper = load_scenario(ROOT / "scenarios/paper.toml")
    assert targets_from_scenario(paper).along_track_error_before_m == 1.95
    table = dict(paper.targets)
    del table["heading_drift_dps"]
    with pytest.raises(ScenarioError, match="heading_drift_dps"):
        targets_from_scenario(scenario_from_dict({"path": dict(paper.path_table), "targets": table}, "t"))
