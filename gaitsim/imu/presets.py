"""Named sensor presets, built from datasheet figures through the same unit parser as scenario files.

| name        | grade        | source |
|-------------|--------------|--------|
| ideal       | no error     | every term off: output equals input exactly |
| vn200       | industrial   | VectorNav VN-200 figures of anchors §5 (secondary copies of the datasheet) |
| paper-vn200 | industrial   | vn200 noise + the seed paper's calibrated b_a, M_a, b_g, M_g, G_g (§II.B) |
| bmi160      | consumer     | Bosch BMI160 data sheet BST-BMI160-DS000 (noise, typical offsets, 16-bit at +-16 g / +-2000 deg/s); UNVERIFIED |
| adis16497   | tactical     | Analog Devices ADIS16497 data sheet Rev. D front page (-1 noise / stability, +-40 g) with the +-2000 deg/s range option; UNVERIFIED |

UNVERIFIED: the bmi160 and adis16497 figures have not been checked against their data sheets' specification
tables (a search of the stored copies reached only their title and feature pages); use them as plausible
consumer- and tactical-grade sensors, not as those parts. Assumptions (not datasheet figures) are stated per
preset in its ``source`` text. Every call of
:func:`get_preset` builds a new immutable :class:`~gaitsim.imu.model.SensorSpec`; customising the result
(``spec.replace(...)``) can never change the preset for a later user.
"""

from __future__ import annotations

from gaitsim.errors import ScenarioError
from gaitsim.imu.model import PARAMETERS, SensorSpec
from gaitsim.imu.units import to_si

# The seed paper's calibration (Wang et al., PLANS 2020, §II.B), in the paper's units.
PAPER_ACCEL_BIAS = [-0.025, -0.0176, 0.1955]  # m/s^2
PAPER_ACCEL_MATRIX = [[1.0020, -0.0083, -0.0042], [0.0055, 0.9986, 0.0051], [0.0067, -0.0039, 0.9964]]
PAPER_GYRO_BIAS = [-0.0893, 0.0375, -0.0412]  # deg/s
PAPER_GYRO_MATRIX = [[0.9972, -0.0041, -0.0067], [0.0041, 0.9972, 0.0052], [0.0067, -0.0027, 1.0019]]
PAPER_G_SENSITIVITY = [[0.0041, 0.0002, -0.0005], [0.0002, 0.0025, 0.0002], [-0.0005, -0.0006, -0.0022]]  # deg/s/(m/s^2)

_VN200 = {
    "gyro_noise_density": (0.0035, "deg/s/sqrt(Hz)"),
    "accel_noise_density": (0.14, "mg/sqrt(Hz)"),
    "gyro_bias_instability": (10.0, "deg/h"),
    "accel_bias_instability": (0.04, "mg"),
    "gyro_bias_instability_tau": (100.0, "s"),
    "accel_bias_instability_tau": (100.0, "s"),
    "gyro_range": (2000.0, "deg/s"),
    "accel_range": (16.0, "g"),
}

_PRESETS: dict[str, tuple[str, dict]] = {
    "ideal": ("no sensor error", {}),
    "vn200": (
        "VectorNav VN-200 (anchors §5, secondary copies of the datasheet): 0.0035 deg/s/sqrt(Hz), "
        "0.14 mg/sqrt(Hz), in-run stability 10 deg/h and 0.04 mg, +-2000 deg/s, +-16 g. Assumed (not in the "
        "datasheet): bias-instability correlation time 100 s; no quantisation (float output), no bandwidth term.",
        _VN200,
    ),
    "paper-vn200": (
        "vn200 noise plus the seed paper's calibration (Wang et al., PLANS 2020, §II.B): b_a (m/s^2), M_a, "
        "b_g (deg/s), M_g, G_g (deg/s per m/s^2)",
        {
            **_VN200,
            "accel_bias": (PAPER_ACCEL_BIAS, "m/s^2"),
            "accel_misalignment": (PAPER_ACCEL_MATRIX, "1"),
            "gyro_bias": (PAPER_GYRO_BIAS, "deg/s"),
            "gyro_misalignment": (PAPER_GYRO_MATRIX, "1"),
            "gyro_g_sensitivity": (PAPER_G_SENSITIVITY, "deg/s/(m/s^2)"),
        },
    ),
    "bmi160": (
        "Bosch BMI160 data sheet (BST-BMI160-DS000): gyro noise 0.007 deg/s/sqrt(Hz), accel noise density "
        "180 ug/sqrt(Hz), typical zero-rate offset 3 deg/s and zero-g offset 40 mg (used here as 1-sigma "
        "turn-on spreads), 16-bit outputs at +-2000 deg/s and +-16 g. UNVERIFIED: not checked against the data sheet's "
        "specification table. No bias-instability figure in the data sheet: left off.",
        {
            "gyro_noise_density": (0.007, "deg/s/sqrt(Hz)"),
            "accel_noise_density": (180.0, "ug/sqrt(Hz)"),
            "gyro_bias_repeatability": (3.0, "deg/s"),
            "accel_bias_repeatability": (40.0, "mg"),
            "gyro_range": (2000.0, "deg/s"),
            "accel_range": (16.0, "g"),
            "gyro_resolution": (4000.0 / 65536.0, "deg/s"),
            "accel_resolution": (32.0 / 65536.0, "g"),
        },
    ),
    "adis16497": (
        "Analog Devices ADIS16497 data sheet Rev. D, features list (UNVERIFIED: not checked against the data sheet "
        "itself): 0.09 deg/sqrt(h) ARW and 0.8 deg/h in-run "
        "stability (ADIS16497-1), accel 13 ug in-run stability, +-40 g; gyro range of the -3 option "
        "(+-2000 deg/s, needed on a foot; the -3 option is noisier than the -1 figures used, so this preset is "
        "optimistic). Assumed (not checked against the data sheet): accel noise 0.008 m/s/sqrt(h), "
        "correlation time 100 s.",
        {
            "gyro_noise_density": (0.09, "deg/sqrt(h)"),
            "accel_noise_density": (0.008, "m/s/sqrt(h)"),
            "gyro_bias_instability": (0.8, "deg/h"),
            "accel_bias_instability": (13.0, "ug"),
            "gyro_bias_instability_tau": (100.0, "s"),
            "accel_bias_instability_tau": (100.0, "s"),
            "gyro_range": (2000.0, "deg/s"),
            "accel_range": (40.0, "g"),
        },
    ),
}

PRESET_NAMES = tuple(_PRESETS)


def get_preset(name: str) -> SensorSpec:
    """A fresh immutable :class:`SensorSpec` for a preset name (see the module table).

    Raises
    ------
    ScenarioError
        for an unknown name, listing the accepted names.
    """
    if name not in _PRESETS:
        raise ScenarioError(f"[sensor] preset: unknown preset {name!r}; choose from {list(PRESET_NAMES)}")
    source, figures = _PRESETS[name]
    parameters = {key: to_si(value, unit, PARAMETERS[key][0], f"preset {name}: {key}")
                  for key, (value, unit) in figures.items()}
    return SensorSpec(name=name, source=source, parameters=parameters)
