"""The one reader of the measured datasets' CSV files: header rows and a numeric table, errors naming the file."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nav.recording import RecordingError


def read_csv(path: Path, header_rows: int = 1, expected_header: list[str] | None = None
             ) -> tuple[list[list[str]], np.ndarray]:
    """Header rows (each split at its commas) and the numbers below them, (rows, columns).

    Raises
    ------
    RecordingError
        naming ``path`` when the file is missing, or when ``expected_header`` is given and the first header row
        differs from it (both shown).
    """
    path = Path(path)
    if not path.exists():
        raise RecordingError(f"{path}: file not found")
    with open(path) as fh:
        header = [fh.readline().strip().split(",") for _ in range(header_rows)]
    if expected_header is not None and header[0] != expected_header:
        raise RecordingError(f"{path}: header {header[0]}, expected {expected_header}")
    return header, np.loadtxt(path, delimiter=",", skiprows=header_rows, ndmin=2)
