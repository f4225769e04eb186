"""A navigation solution and its files: ``solution.csv`` and ``score.json``.

``solution.csv`` columns: ``t, pos_x, pos_y, pos_z, vel_x, vel_y, vel_z, q_w, q_x, q_y, q_z, zupt`` -- s, m and
m/s in the world frame (ENU), attitude body->world (w, x, y, z), 1 where the ZUPT was applied. Rows before the
navigation start (the first stationary window) are omitted.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .files import atomic_output_dir, write_json
from .recording import read_csv, write_csv

SOLUTION_COLUMNS = ("t", "pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z", "q_w", "q_x", "q_y", "q_z", "zupt")


@dataclass
class Solution:
    """Output of :func:`nav.pipeline.navigate`.

    Attributes
    ----------
    t : (N,) s, the recording's timestamps.
    pos : (N, 3) m, vel : (N, 3) m/s, quat : (N, 4) -- world ENU, body->world; NaN before ``start``.
    stationary : (N,) bool, samples where the ZUPT was applied.
    start : first navigated sample (start of the alignment window).
    bias_acc : (3,) m/s^2, bias_gyr : (3,) rad/s, gsens : (9,) rad/s per m/s^2 -- final estimates (zero when the
        filter does not estimate them).
    info : dict, everything needed to reproduce and read the run (detector parameters, filter configuration,
        mechanisation, alignment, compensation, warnings).
    """

    t: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    quat: np.ndarray
    stationary: np.ndarray
    start: int
    bias_acc: np.ndarray
    bias_gyr: np.ndarray
    gsens: np.ndarray
    info: dict = field(default_factory=dict)

    def table(self) -> np.ndarray:
        """(N - start, 12) rows of solution.csv."""
        s = slice(self.start, None)
        return np.column_stack([self.t[s], self.pos[s], self.vel[s], self.quat[s], self.stationary[s].astype(float)])


def write_solution_into(folder: Path, solution: Solution, score: dict) -> None:
    """Write ``solution.csv`` and ``score.json`` into an existing (temporary) folder; prefer write_solution."""
    folder = Path(folder)
    write_csv(folder / "solution.csv", SOLUTION_COLUMNS, solution.table())
    write_json(folder / "score.json", score)


def write_solution(folder: str | Path, solution: Solution, score: dict, overwrite: bool = False) -> Path:
    """Write ``solution.csv`` and ``score.json`` into ``folder`` atomically (nothing appears on failure)."""
    with atomic_output_dir(folder, overwrite) as tmp:
        write_solution_into(tmp, solution, score)
    return Path(folder)


def read_solution_csv(path: str | Path) -> np.ndarray:
    """The (M, 12) table of a solution.csv (columns ``SOLUTION_COLUMNS``); RecordingError on another layout."""
    return read_csv(Path(path), SOLUTION_COLUMNS)
