"""Datasheet units, the [sensor] table, presets and their immutability."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from gaitsim.errors import ScenarioError
from gaitsim.imu.config import changed_sensor, sensor_from_table, sensor_table
from gaitsim.imu.presets import PAPER_G_SENSITIVITY, PRESET_NAMES, get_preset
from gaitsim.imu.units import STANDARD_GRAVITY, to_si

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def test_unit_conversions():
    # deg/sqrt(h) = 60 x deg/s/sqrt(Hz) (anchors §5): 0.21 deg/sqrt(h) is the VN-200's 0.0035 deg/s/sqrt(Hz)
    arw = to_si(0.21, "deg/sqrt(h)", "gyro_noise_density", "k")
    density = to_si(0.0035, "deg/s/sqrt(Hz)", "gyro_noise_density", "k")
    assert arw == pytest.approx(density, rel=1e-12)
    assert to_si(1.0, "mg", "acceleration", "k") == pytest.approx(1e-3 * STANDARD_GRAVITY)
    assert to_si(1.0, "deg/h", "angular_rate", "k") == pytest.approx(np.pi / 180 / 3600)
    assert to_si(1.0, "deg/s/g", "g_sensitivity", "k") == pytest.approx(np.pi / 180 / STANDARD_GRAVITY)
    assert to_si(100.0, "ug/√Hz", "accel_noise_density", "k") == pytest.approx(1e-4 * STANDARD_GRAVITY)
    assert to_si(0.1, "°/h/√h", "gyro_random_walk", "k") == pytest.approx(np.deg2rad(0.1) / 3600 / 60)
    assert to_si(50.0, "ppm", "ratio", "k") == pytest.approx(5e-5)


@pytest.mark.parametrize("key, value, expected", [
    ("gyro_noise_density", [0.1, "mg"], r"\[sensor\] gyro_noise_density: unit 'mg' has the dimension of "
                                        r"acceleration.*accepted units: \['rad/s/sqrt\(Hz\)'"),
    ("accel_bias", [1.0, "furlong"], r"\[sensor\] accel_bias: unit 'furlong' is not a known unit; "
                                     r"accepted units: \['m/s\^2', 'mm/s\^2', 'g', 'mg', 'ug'\]"),
    ("gyro_bias", 0.1, r"\[sensor\] gyro_bias: expected \[value, \"unit\"\], got 0.1; accepted units"),
    ("gyro_bias", [0.1, 3], r"\[sensor\] gyro_bias: expected \[value, \"unit\"\]"),
    ("accel_misalignment", [[1, 0, 0], "1"], r"accel_misalignment: expected shape \(3, 3\)"),
    ("gyro_range", [-5.0, "deg/s"], r"gyro_range: value .* must be > 0"),
    ("accel_bias", [["a", 1, 2], "mg"], r"accel_bias: value .* is not a number"),
    ("accel_bias", [["1", 1, 2], "mg"], r"accel_bias: value .* is not a number"),
    ("gyro_bias", [float("inf"), "deg/s"], r"gyro_bias: value \[inf, inf, inf\] must be finite"),
])
def test_bad_values_refused_with_key_value_and_accepted_units(key, value, expected):
    with pytest.raises(ScenarioError, match=expected):
        sensor_from_table({"preset": "vn200", key: value})


def test_bad_keys_and_choices_refused():
    with pytest.raises(ScenarioError, match=r"unknown key\(s\) \['gyro_nois'\]; accepted keys: \['preset'"):
        sensor_from_table({"gyro_nois": [1, "deg/h"]})
    with pytest.raises(ScenarioError, match=r"preset: 'vn100' is not a preset; choose from \['ideal', 'vn200'"):
        sensor_from_table({"preset": "vn100"})
    with pytest.raises(ScenarioError, match="withhold: expected true or false, got 'yes'"):
        sensor_from_table({"withhold": "yes"})
    with pytest.raises(ScenarioError, match="filter_order: expected an integer in 1..8, got 9"):
        sensor_from_table({"filter_order": 9})


def test_overrides_in_datasheet_units_become_si():
    spec = sensor_from_table({
        "preset": "vn200",
        "accel_bias": [[1, 2, 3], "mg"],
        "gyro_g_sensitivity": [PAPER_G_SENSITIVITY, "deg/s/(m/s^2)"],
        "gyro_bandwidth": [200, "Hz"],
        "accel_range": [float("inf"), "g"],
    })
    np.testing.assert_allclose(spec["accel_bias"], np.array([1, 2, 3]) * 1e-3 * STANDARD_GRAVITY)
    np.testing.assert_allclose(spec["gyro_g_sensitivity"], np.deg2rad(PAPER_G_SENSITIVITY))
    assert spec["gyro_bandwidth"] == 200.0 and np.isinf(spec["accel_range"])
    np.testing.assert_allclose(spec["gyro_noise_density"], get_preset("vn200")["gyro_noise_density"])


def test_declared_metadata_in_si_or_withheld():
    declared = sensor_from_table({"preset": "paper-vn200"}).declared()
    assert declared["parameters"]["gyro_bias"]["unit"] == "rad/s"
    np.testing.assert_allclose(declared["parameters"]["gyro_bias"]["value"], np.deg2rad([-0.0893, 0.0375, -0.0412]))
    assert declared["parameters"]["gyro_bandwidth"]["value"] == "inf"
    assert sensor_from_table({"preset": "paper-vn200", "withhold": True}).declared() == {"withheld": True}


def test_presets_are_immutable_and_customising_never_leaks():
    original = np.array(get_preset("vn200")["gyro_noise_density"])
    custom = get_preset("vn200").replace(gyro_noise_density=1.0)
    sensor_from_table({"preset": "vn200", "gyro_noise_density": [1.0, "deg/s/sqrt(Hz)"]})
    assert custom["gyro_noise_density"][0] == 1.0
    np.testing.assert_array_equal(get_preset("vn200")["gyro_noise_density"], original)
    spec = get_preset("vn200")
    with pytest.raises(ValueError):
        spec["gyro_noise_density"][0] = 5.0
    with pytest.raises(TypeError):
        spec.parameters["gyro_noise_density"] = 5.0
    with pytest.raises(AttributeError):
        spec.name = "other"
    np.testing.assert_array_equal(get_preset("vn200")["gyro_noise_density"], original)


def test_every_preset_builds_and_names_its_source():
    for name in PRESET_NAMES:
        spec = get_preset(name)
        assert spec.name == name and spec.source
    paper = get_preset("paper-vn200")
    np.testing.assert_allclose(paper["gyro_bias"], np.deg2rad([-0.0893, 0.0375, -0.0412]))
    np.testing.assert_allclose(paper["gyro_noise_density"], get_preset("vn200")["gyro_noise_density"])


@pytest.mark.parametrize("file, preset", [("static_10min_vn200.toml", "vn200"),
                                          ("straight_100m_paper.toml", "paper-vn200")])
def test_shipped_scenarios_select_their_preset(file, preset):
    scenario = tomllib.loads((SCENARIOS / file).read_text())
    spec = sensor_from_table(scenario["sensor"], where=f"{file} [sensor]")
    assert spec.name == preset and scenario["sampling"]["rate_hz"] == 800.0


def test_a_sensor_change_may_set_the_filter_order_and_nothing_else_plain():
    """The loop's first-order bandwidth effect changes filter_order on the twin's existing sensor."""
    base = get_preset("bmi160")
    changed = changed_sensor(base, {"accel_bandwidth": [25.0, "Hz"], "filter_order": 1})
    assert changed.filter_order == 1 and changed["accel_bandwidth"] == pytest.approx(25.0)
    assert base.filter_order == 2
    with pytest.raises(ScenarioError, match="filter_order"):
        changed_sensor(base, {"filter_order": 0})
    with pytest.raises(ScenarioError, match="preset"):
        changed_sensor(base, {"preset": "vn200"})


def test_the_filter_kind_is_read_checked_and_written_back():
    """filter_kind: "digital" (default) or "analogue"; a sensor change may set it; the [sensor] table that
    rebuilds a spec carries it when it is not the default."""
    assert sensor_from_table({}).filter_kind == "digital"
    spec = sensor_from_table({"preset": "bmi160", "filter_order": 1, "filter_kind": "analogue"})
    assert spec.filter_kind == "analogue" and sensor_from_table(sensor_table(spec)).filter_kind == "analogue"
    assert "filter_kind" not in sensor_table(get_preset("bmi160"))
    assert changed_sensor(get_preset("bmi160"), {"filter_kind": "analogue"}).filter_kind == "analogue"
    with pytest.raises(ScenarioError, match="filter_kind: expected one of \\['digital', 'analogue'\\], got 'rc'"):
        sensor_from_table({"filter_kind": "rc"})
    with pytest.raises(ScenarioError, match="filter_kind"):
        changed_sensor(get_preset("bmi160"), {"filter_kind": 1})
