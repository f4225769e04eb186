"""IMU error model, datasheet units, presets and the simulated calibration lab."""

from nav.lazy import lazy_exports

# each name is imported from its module on first use (simulating a walk does not need the calibration lab)
_EXPORTS = {
    "calibration_lab": ("ShakerResult", "run_lab", "shaker_g_sensitivity"),
    "config": ("sensor_from_table",),
    "model": ("SensorSpec", "apply_sensor"),
    "presets": ("PRESET_NAMES", "get_preset"),
}
__all__, __getattr__ = lazy_exports(__name__, _EXPORTS)
