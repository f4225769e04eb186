"""Bring your own data (``gaitsim import``): axis maps, unit conversion, the checks and their suggestions.

Acceptance: a logger file with millisecond timestamps, g, deg/s and turned axes (made from x-io's NGIMU walk)
imports, navigates and scores exactly as the built-in x-io loader's recording does.
"""

import itertools
import warnings

import numpy as np
import pytest

from conftest import DATA, needs_data
from gaitsim.cli import main
from gaitsim.measured.axes import AxisMapError, apply_axis_map, axis_map_text, is_mirror, parse_axis_map
from gaitsim.measured.importer import ImportSpec, LoggerFileError, import_csv
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk
from nav import navigate, score_solution
from nav.constants import STANDARD_GRAVITY
from nav.recording import read_recording

SIGNED_PERMUTATIONS = [np.diag(signs)[list(order)] for order in itertools.permutations(range(3))
                       for signs in itertools.product((1.0, -1.0), repeat=3)]
LOGGER_AXES = "y,-x,z"  # the logger's x points to the right of the foot, its y toward the toes


def to_logger(v: np.ndarray) -> np.ndarray:
    """Body-frame vectors in the logger's axes (file x = -body y, file y = body x, file z = body z)."""
    return np.column_stack([-v[:, 1], v[:, 0], v[:, 2]])


def write_logger_csv(path, t_ms, acc_g, gyr_dps):
    np.savetxt(path, np.column_stack([t_ms, to_logger(acc_g), to_logger(gyr_dps)]), delimiter=",", fmt="%.17g",
               header="timestamp_ms,ax,ay,az,gx,gy,gz", comments="")


LOGGER_OPTIONS = ["--time", "timestamp_ms", "--time-unit", "ms", "--acc", "ax,ay,az", "--acc-unit", "g",
                  "--gyr", "gx,gy,gz", "--gyr-unit", "deg/s"]


def map_text(m: np.ndarray) -> str:
    """The axis-map text of a signed permutation, written without the parser's checks."""
    return ",".join(("-" if row[np.argmax(np.abs(row))] < 0 else "") + "xyz"[np.argmax(np.abs(row))] for row in m)


def test_axis_maps_are_the_48_signed_permutations_24_of_them_mirrors_and_round_trip():
    v = np.random.default_rng(0).normal(size=(50, 3))
    for m in SIGNED_PERMUTATIONS:
        np.testing.assert_array_equal(parse_axis_map(map_text(m)), m)
        assert axis_map_text(m) == map_text(m)
        np.testing.assert_array_equal(apply_axis_map(m, v), v @ m.T)  # exact: a signed permutation
    assert len(SIGNED_PERMUTATIONS) == 48
    assert sum(is_mirror(m) for m in SIGNED_PERMUTATIONS) == 24
    np.testing.assert_array_equal(apply_axis_map(parse_axis_map(LOGGER_AXES), to_logger(v)), v)


@pytest.mark.parametrize("text, message", [("x,y", "expected three"), ("x,x,z", "exactly once"),
                                           ("x,y,w", "'w'"), ("x,--y,z", "'--y'"), ("x,y,", "''")])
def test_bad_axis_maps_are_refused_naming_the_entry(text, message):
    with pytest.raises(AxisMapError, match=message):
        parse_axis_map(text)


@pytest.fixture(scope="module")
def walk():
    """A short simulated walk (ideal sensor, 200 Hz) and its logger file (ms, g, deg/s, turned axes)."""
    doc = {"scenario": {"name": "import", "seed": 5}, "path": {"kind": "straight", "length_m": 6.0},
           "gait": {"stand_start_s": 1.0, "stand_end_s": 1.0}, "sampling": {"rate_hz": 200.0}}
    return simulate_walk(scenario_from_dict(doc, "import"))


def test_logger_file_converts_exactly_to_si_and_the_body_frame(walk, tmp_path):
    src = tmp_path / "logger.csv"
    write_logger_csv(src, walk.t * 1e3, walk.acc / STANDARD_GRAVITY, np.degrees(walk.gyr))
    assert main(["import", str(src), "--out", str(tmp_path / "rec"), "--axes", LOGGER_AXES] + LOGGER_OPTIONS) == 0
    rec = read_recording(tmp_path / "rec")
    np.testing.assert_allclose(rec.t, walk.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec.acc, walk.acc, rtol=1e-15, atol=1e-14)
    np.testing.assert_allclose(rec.gyr, walk.gyr, rtol=1e-15, atol=1e-15)
    report = rec.meta["import"]
    assert report["factors_to_si"] == {"time": 1e-3, "acceleration": STANDARD_GRAVITY,
                                       "angular_rate": np.pi / 180}
    assert report["axis_matrix"] == [[0, 1, 0], [-1, 0, 0], [0, 0, 1]] and report["rows_dropped"] == 0
    assert report["timing"]["rate_hz"] == pytest.approx(200.0, rel=1e-9)
    assert "x 0.001" in (tmp_path / "rec/import-report.md").read_text()


@pytest.mark.parametrize("change, message", [
    ({"axes": "x,y,z"}, "--axes y,-x,z passes them"),
    ({"time_unit": "s"}, "--time-unit ms (giving 200 Hz) would fit"),
    ({"acc_unit": "m/s^2"}, "--acc-unit g (giving 9.81 m/s^2) would fit"),
    ({"gyr_unit": "rad/s"}, "--gyr-unit deg/s"),
    ({"acc_unit": "furlong"}, "accepted units"),
])
def test_a_wrong_setting_is_refused_with_what_would_fit_and_nothing_is_written(walk, tmp_path, change, message,
                                                                               capsys):
    src = tmp_path / "logger.csv"
    write_logger_csv(src, walk.t * 1e3, walk.acc / STANDARD_GRAVITY, np.degrees(walk.gyr))
    options = dict(zip(LOGGER_OPTIONS[::2], LOGGER_OPTIONS[1::2]))
    options["--axes"] = LOGGER_AXES
    options.update({"--" + key.replace("_", "-"): value for key, value in change.items()})
    argv = ["import", str(src), "--out", str(tmp_path / "rec")] + [x for kv in options.items() for x in kv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err
    assert not (tmp_path / "rec").exists()


def test_repeated_times_and_nans_are_refused_with_counts(walk, tmp_path):
    t_ms = walk.t * 1e3
    t_ms[10:13] = t_ms[9]  # three repeated packets
    src = tmp_path / "logger.csv"
    write_logger_csv(src, t_ms, walk.acc / STANDARD_GRAVITY, np.degrees(walk.gyr))
    spec = ImportSpec(time_column="timestamp_ms", acc_columns=("ax", "ay", "az"), gyr_columns=("gx", "gy", "gz"),
                      time_unit="ms", acc_unit="g", gyr_unit="deg/s", axes=LOGGER_AXES)
    with pytest.raises(LoggerFileError, match="3 rows whose time does not increase .3 repeat"):
        import_csv(src, spec)
    rec, report = import_csv(src, ImportSpec(**{**spec.__dict__, "drop_repeated": True}))
    assert report.rows_dropped == 3 and rec.n == walk.n - 3 and "dropped 3 of" in report.warnings[0]
    acc = walk.acc / STANDARD_GRAVITY
    acc[[20, 21], 2] = np.nan
    write_logger_csv(src, walk.t * 1e3, acc, np.degrees(walk.gyr))
    with pytest.raises(LoggerFileError, match=r"NaN samples per column \{'az': 2\}"):
        import_csv(src, spec)


def test_a_file_without_time_column_takes_the_rate(walk, tmp_path):
    src = tmp_path / "plain.csv"
    np.savetxt(src, np.column_stack([walk.acc, walk.gyr]), delimiter=";", fmt="%.17g",
               header="acc_x;acc_y;acc_z;gyr_x;gyr_y;gyr_z", comments="")
    rec, _ = import_csv(src, ImportSpec(time_column=None, rate_hz=200.0, delimiter=";"))
    np.testing.assert_allclose(rec.t, walk.t, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(rec.acc, walk.acc)


@needs_data("xio-ngimu")
def test_xio_as_a_logger_file_navigates_like_the_built_in_loader(tmp_path):
    from gaitsim.measured import load_dataset

    raw = np.loadtxt(DATA / "xio-ngimu/short_walk.csv", delimiter=",", skiprows=1)  # s, deg/s, g as stored
    src = tmp_path / "logger.csv"
    write_logger_csv(src, raw[:, 0] * 1e3, raw[:, 4:7], raw[:, 1:4])
    out = tmp_path / "walk"
    assert main(["import", str(src), "--out", str(out), "--axes", LOGGER_AXES, "--drop-repeated", "--loop-closure"]
                + LOGGER_OPTIONS) == 0
    imported = read_recording(out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loader's data-quality counts are in meta
        builtin = {r.meta["recording"]: r for r in load_dataset("xio-ngimu", DATA)}["short_walk"]
        assert imported.meta["import"]["rows_dropped"] == builtin.meta["data_quality"]["dropped_rows"] == 205
        np.testing.assert_allclose(imported.t, builtin.t, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(imported.acc, builtin.acc)
        np.testing.assert_array_equal(imported.gyr, builtin.gyr)
        ours, theirs = navigate(imported), navigate(builtin)
        np.testing.assert_allclose(ours.pos, theirs.pos, rtol=0, atol=1e-9)
        assert score_solution(imported, ours)["final_error_m"] == pytest.approx(
            score_solution(builtin, theirs)["final_error_m"], abs=1e-9)
