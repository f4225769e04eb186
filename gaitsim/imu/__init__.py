"""IMU error model, datasheet units, presets and the simulated calibration lab."""

from importlib import import_module

# each name is imported from its module on first use (the calibration lab's Allan fits need scipy.optimize,
# which simulating a walk does not)
_EXPORTS = {
    "calibration_lab": ("ShakerResult", "run_lab", "shaker_g_sensitivity"),
    "config": ("sensor_from_table",),
    "model": ("SensorSpec", "apply_sensor"),
    "presets": ("PRESET_NAMES", "get_preset"),
}
_MODULE_OF = {name: module for module, names in _EXPORTS.items() for name in names}
__all__ = sorted(_MODULE_OF)


def __getattr__(name: str):
    if name in _MODULE_OF:
        return getattr(import_module(f".{_MODULE_OF[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
