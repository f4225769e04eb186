"""IMU error model, datasheet units, presets and the simulated calibration lab."""
