"""The loop's inputs: the --axes map, the sensor-frame laws, reference kinds and bad recordings refused cleanly."""

import dataclasses

import numpy as np
import pytest

from gaitsim.cli import main
from gaitsim.loop import blind, frame, navigation
from gaitsim.measured import axes
from nav.recording import Recording, Reference, RecordingError, write_recording


@pytest.fixture(scope="module")
def walk():
    rec = blind.base_recording("paper-vn200")
    return Recording(rec.t, rec.acc, rec.gyr, meta={}, reference=rec.reference)


def test_axis_map_parses_formats_and_maps_both_sensors(walk):
    m = axes.parse_axis_map("y,-x,z")
    np.testing.assert_array_equal(m, [[0, 1, 0], [-1, 0, 0], [0, 0, 1]])
    assert axes.axis_map_text(m) == "y,-x,z"
    mapped = axes.remapped(walk, m)
    np.testing.assert_array_equal(mapped.acc[:, 1], -walk.acc[:, 0])
    np.testing.assert_array_equal(mapped.gyr[:, 0], walk.gyr[:, 1])
    assert mapped.meta["axes"] == "y,-x,z"


@pytest.mark.parametrize("text", ["x,y", "x,x,z", "a,b,c", "x,--y,z", ""])
def test_malformed_axis_map_is_refused_naming_it(text):
    with pytest.raises(axes.AxisMapError, match="axis map"):
        axes.parse_axis_map(text)


@pytest.mark.parametrize("text", ["x,y,z", "x,-y,-z", "y,-x,z", "-x,-y,z", "x,y,-z", "y,x,z", "z,y,-x", "-y,x,z"])
def test_frame_check_finds_the_map_back_to_the_body_frame(walk, text):
    """Law: whatever signed permutation (mirrors included) the logger applied, the check's map undoes it."""
    applied = axes.parse_axis_map(text)
    found = frame.check_frame(axes.remapped(walk, applied))
    np.testing.assert_array_equal(found.axes @ applied, np.eye(3))
    assert found.is_body_frame == (text == "x,y,z")


def test_a_z_down_recording_is_refused_with_the_map_and_accepted_with_it(walk):
    z_down = axes.remapped(walk, axes.parse_axis_map("x,-y,-z"))
    with pytest.raises(frame.FrameError, match="--axes x,-y,-z"):
        frame.require_body_frame(z_down)
    fixed, check = frame.require_body_frame(z_down, "x,-y,-z")
    np.testing.assert_allclose(fixed.acc, walk.acc, atol=1e-12)
    assert check.is_body_frame


def test_reference_kinds(walk):
    assert navigation.nav_reference(walk).kind == "track"
    ends = dataclasses.replace(walk, reference=Reference(walk.reference.t[[0, -1]], walk.reference.pos[[0, -1]]))
    assert navigation.nav_reference(ends).kind == "endpoints"
    assert navigation.nav_reference(dataclasses.replace(walk, reference=None)).kind == "none"
    assert navigation.nav_reference(walk, 20.0) == navigation.NavReference("distance", 20.0)
    with pytest.raises(RecordingError, match="--distance -3"):
        navigation.nav_reference(walk, -3.0)


def test_distance_ratio_of_an_exact_distance_is_the_track_ratio(walk):
    """Law: --distance equal to the walked stance-to-stance path gives the track's stride-length ratio."""
    track, sol = navigation.navigation_metrics(walk, navigation.NavReference("track"))
    bare = dataclasses.replace(walk, reference=None)
    true_path = navigation._stance_path_m(sol) / track["nav_length_ratio"]
    by_distance, _ = navigation.navigation_metrics(bare, navigation.NavReference("distance", true_path))
    assert by_distance["nav_length_ratio"] == pytest.approx(track["nav_length_ratio"], rel=1e-9)
    assert 0.9 < track["nav_length_ratio"] < 1.1


@pytest.mark.parametrize("damage", ["nan", "deg_per_s", "z_down", "truncated"])
def test_bad_recordings_fail_cleanly_with_nothing_written(walk, tmp_path, capsys, damage):
    acc, gyr, t = walk.acc.copy(), walk.gyr.copy(), walk.t
    if damage == "nan":
        acc[400:403] = np.nan
    elif damage == "deg_per_s":
        gyr = np.degrees(gyr)
    elif damage == "z_down":
        acc, gyr = acc * [1, -1, -1], gyr * [1, -1, -1]
    else:
        t, acc, gyr = t[:300], acc[:300], gyr[:300]
    write_recording(Recording(t, acc, gyr, meta={}), tmp_path / "rec")
    code = main(["loop", str(tmp_path / "rec"), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code != 0 and "every recording failed" in err
    assert {"nan": "NaN", "deg_per_s": "deg/s", "z_down": "--axes x,-y,-z", "truncated": "strides"}[damage] in err
    assert not (tmp_path / "out").exists()
