"""gaitsim: ground-truth foot-mounted IMU simulation (MuJoCo), IMU error model, experiments, sim-to-real loop."""

__version__ = "0.1.0"
