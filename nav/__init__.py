"""nav: the shared ZUPT-aided navigation filter.

Reads any recording (simulated or measured) and never imports the simulator (``gaitsim``).
"""

from .detectors import DetectorParams, DetectorResult, convert_threshold, detect, oracle
from .ekf import FilterConfig, FilterOutput, run_filter, run_filter_batch
from .pipeline import NavOptions, navigate, navigate_batch, run, score_solution
from .solution import Solution, write_solution
from .strapdown import integrate

__all__ = [
    "DetectorParams", "DetectorResult", "convert_threshold", "detect", "oracle",
    "FilterConfig", "FilterOutput", "run_filter", "run_filter_batch",
    "NavOptions", "navigate", "navigate_batch", "run", "score_solution",
    "Solution", "write_solution", "integrate",
]
