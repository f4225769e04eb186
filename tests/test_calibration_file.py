"""nav.calibration: the deterministic equation, its exact inverse per term group, and the JSON file."""

import json

import numpy as np
import pytest

from gaitsim.imu.presets import get_preset
from nav.calibration import Calibration, CalibrationError, load_calibration, save_calibration


def paper_calibration(with_g2=True) -> Calibration:
    cal = get_preset("paper-vn200").deterministic()
    g2 = np.array([[2e-6, 1e-7, 0.0], [0.0, -1e-6, 3e-7], [5e-7, 0.0, 1e-6]]) if with_g2 else None
    return Calibration(b_a=cal.b_a, M_a=cal.M_a, b_g=cal.b_g, M_g=cal.M_g, G_g=cal.G_g, G2_g=g2,
                       sigma={"G_g": np.full((3, 3), 1e-6)}, source="test")


def samples(n=500, seed=0):
    rng = np.random.default_rng(seed)
    return rng.normal(0, 30.0, (n, 3)) + [0, 0, 9.81], rng.normal(0, 5.0, (n, 3))


def test_inverse_of_forward_is_identity_to_1e12():
    cal = paper_calibration()
    acc, gyr = samples()
    acc_c, gyr_c = cal.correct(*cal.distort(acc, gyr))
    np.testing.assert_allclose(acc_c, acc, rtol=0, atol=1e-12)
    np.testing.assert_allclose(gyr_c, gyr, rtol=0, atol=1e-12)


def test_forward_equation_written_out():
    cal = paper_calibration()
    acc, gyr = samples(n=3)
    acc_m, gyr_m = cal.distort(acc, gyr)
    for f, w, fm, wm in zip(acc, gyr, acc_m, gyr_m):
        np.testing.assert_allclose(fm, cal.M_a @ f + cal.b_a, atol=1e-12)
        np.testing.assert_allclose(wm, cal.M_g @ w + cal.G_g @ f + cal.G2_g @ (f * f) + cal.b_g, atol=1e-12)


@pytest.mark.parametrize("g_sensitivity", [0.0, 1e-3])
def test_an_identity_matrix_skipped_gives_the_bits_of_the_blas_product(g_sensitivity):
    """distort skips a product by an exact identity when every bias element is nonzero and the input finite; the
    output is byte for byte that of the product (signed zeros in the input), and a non-finite input or a zero
    bias element still takes it (an inf spreads NaN across its row)."""
    acc, gyr = samples(n=2000)
    acc[::5], gyr[::3], gyr[1::7, 1] = -0.0, 0.0, -0.0

    def blas_route(cal, acc, gyr):
        acc_m, gyr_m = acc @ cal.M_a.T, gyr @ cal.M_g.T
        gyr_m += acc @ cal.G_g.T if g_sensitivity else 0.0
        for c in range(3):
            acc_m[:, c] += cal.b_a[c]
            gyr_m[:, c] += cal.b_g[c]
        return acc_m, gyr_m

    infinite = acc.copy()
    infinite[7, 0] = np.inf
    for b_a, b_g, acc_in in (([0.1, -0.2, 1e-9], [1e-3, -2e-3, 3e-3], acc), ([0.1, -0.0, 1e-9], [0.0, 1.0, 2.0], acc),
                             ([0.1, -0.2, 1e-9], [1e-3, -2e-3, 3e-3], infinite)):
        cal = Calibration(b_a=b_a, M_a=np.eye(3), b_g=b_g, M_g=np.eye(3), G_g=np.full((3, 3), g_sensitivity))
        ours = cal.distort(acc_in, gyr)
        for got, expected in zip(ours, blas_route(cal, acc_in, gyr)):
            assert got.tobytes() == expected.tobytes()
    assert np.isnan(ours[0][7, 1])  # the inf's row: NaN, as the product makes it


def test_distort_never_writes_into_its_inputs_even_where_the_identity_product_is_skipped(tmp_path):
    """The skipped product is the input's own memory; a view of it (a memory-mapped file, a DataFrame's values)
    must come out of distort untouched, and a read-only one must not be written either."""
    acc, gyr = samples(n=500)
    cal = Calibration(b_a=[0.1, -0.2, 0.3], M_a=np.eye(3), b_g=[1e-3, -2e-3, 3e-3], M_g=np.eye(3), G_g=np.zeros((3, 3)))
    path = tmp_path / "acc.npy"
    np.save(path, acc)
    for mode in ("r+", "r"):
        mapped = np.load(path, mmap_mode=mode)
        acc_m, _ = cal.distort(mapped, gyr)
        np.testing.assert_array_equal(np.load(path), acc)
        np.testing.assert_array_equal(acc_m, acc + cal.b_a)


def test_terms_left_out_are_not_corrected():
    cal = paper_calibration(with_g2=False)
    acc, gyr = samples()
    acc_m, gyr_m = cal.distort(acc, gyr)
    acc_c, gyr_c = cal.correct(acc_m, gyr_m, terms=("bias", "misalignment"))
    np.testing.assert_allclose(acc_c, acc, atol=1e-12)  # accelerometer has no g-sensitivity term
    np.testing.assert_allclose(gyr_c - gyr, np.linalg.solve(cal.M_g, (acc @ cal.G_g.T).T).T, atol=1e-12)
    _, gyr_b = cal.correct(acc_m, gyr_m, terms=("bias",))
    np.testing.assert_allclose(gyr_b, gyr_m - cal.b_g, atol=0)
    with pytest.raises(CalibrationError, match=r"unknown \['scale'\]"):
        cal.correct(acc_m, gyr_m, terms=("scale",))


def test_identity_changes_nothing():
    acc, gyr = samples()
    acc_c, gyr_c = Calibration.identity().correct(acc, gyr)
    np.testing.assert_allclose(acc_c, acc, atol=1e-14)
    np.testing.assert_allclose(gyr_c, gyr, atol=1e-14)


def test_save_and_load_round_trip_with_units(tmp_path):
    cal = paper_calibration()
    path = save_calibration(cal, tmp_path / "cal.json")
    data = json.loads(path.read_text())
    assert data["terms"]["G_g"]["unit"] == "rad/s/(m/s^2)" and data["terms"]["b_g"]["unit"] == "rad/s"
    back = load_calibration(path)
    for name in ("b_a", "M_a", "b_g", "M_g", "G_g", "G2_g"):
        np.testing.assert_array_equal(getattr(back, name), getattr(cal, name))
    np.testing.assert_array_equal(back.sigma["G_g"], cal.sigma["G_g"])
    assert back.source == "test" and list(tmp_path.iterdir()) == [path]


def test_bad_files_name_file_and_key(tmp_path):
    path = save_calibration(paper_calibration(), tmp_path / "cal.json")
    data = json.loads(path.read_text())
    data["terms"]["b_g"]["unit"] = "deg/s"
    path.write_text(json.dumps(data))
    with pytest.raises(CalibrationError, match=r"cal.json: key 'terms.b_g.unit' must be 'rad/s', got 'deg/s'"):
        load_calibration(path)
    data["terms"]["b_g"]["unit"] = "rad/s"
    data["terms"]["M_a"]["value"] = [[1, 0], [0, 1]]
    path.write_text(json.dumps(data))
    with pytest.raises(CalibrationError, match=r"cal.json: key 'terms.M_a: expected shape \(3, 3\)"):
        load_calibration(path)
    del data["terms"]["G_g"]
    path.write_text(json.dumps(data))
    with pytest.raises(CalibrationError, match=r"cal.json: key 'terms.G_g' missing"):
        load_calibration(path)
    path.write_text("{not json")
    with pytest.raises(CalibrationError, match="cal.json: not valid JSON"):
        load_calibration(path)
    with pytest.raises(CalibrationError, match="nothere.json: calibration file not found"):
        load_calibration(tmp_path / "nothere.json")


def test_calibration_is_frozen():
    cal = paper_calibration()
    with pytest.raises(ValueError):
        cal.G_g[0, 0] = 1.0
    with pytest.raises(AttributeError):
        cal.source = "x"
