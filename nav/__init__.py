"""nav: the shared ZUPT-aided navigation filter.

Reads any recording (simulated or measured) and never imports the simulator (``gaitsim``).

Modules: ``recording`` (the folder format), ``checks`` (bad input), ``calibration`` (step 1), ``detectors``,
``alignment``, ``strapdown``, ``ekf`` (compiled loops in ``_numba``), ``zupt_velocity`` (step 2),
``pipeline`` (recording -> solution), ``metrics``, ``solution``, ``command`` (``gaitsim nav``), and the shared
helpers ``constants``, ``files``, ``lazy``, ``quaternion`` and ``series``.

Names and units: one base name per quantity, from the command line through Python to JSON. Inside Python
every value is in SI units (m, s, rad, m/s^2, rad/s) and the name carries no unit (``sigma_g`` in rad/s,
``heading`` in rad). Where a boundary takes another unit (command line, TOML), the unit is appended to the
base name and the value is converted once there: ``--sigma-g-dps`` / ``sigma_g_dps`` (deg/s),
``--heading-deg`` (deg). JSON keys may carry an SI unit suffix for the reader (``sigma_g_rad_s``,
``final_error_m``). Example: the velocity the ZUPT applies during stance is ``stance_velocity`` everywhere
(NavOptions, run_filter, the compiled filter, ``--stance-velocity``, the ``info`` key); its models have a
``stance_velocity(stationary)`` method.
"""

from .lazy import lazy_exports

# the package's main names, each imported from its module on first use (``import nav.recording`` then loads
# no filter, detector or scipy module it does not need)
_EXPORTS = {
    "detectors": ("DetectorParams", "DetectorResult", "convert_threshold", "detect", "oracle"),
    "ekf": ("FilterConfig", "FilterOutput", "run_filter", "run_filter_batch"),
    "pipeline": ("HeadingSource", "NavOptions", "navigate", "navigate_variants", "run", "run_variants",
                 "score_solution"),
    "solution": ("Solution", "write_solution"),
    "strapdown": ("integrate",),
}
__all__, __getattr__ = lazy_exports(__name__, _EXPORTS)
