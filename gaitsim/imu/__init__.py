"""IMU error model, datasheet units, presets and the simulated calibration lab."""

from gaitsim.imu.calibration_lab import ShakerResult, run_lab, shaker_g_sensitivity
from gaitsim.imu.config import sensor_from_table
from gaitsim.imu.model import SensorSpec, apply_sensor
from gaitsim.imu.presets import PRESET_NAMES, get_preset

__all__ = ["PRESET_NAMES", "SensorSpec", "ShakerResult", "apply_sensor", "get_preset", "run_lab",
           "sensor_from_table", "shaker_g_sensitivity"]
