"""What the tests share: where the measured datasets live, and a mark that skips a test without them."""

from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"  # shared/ beside the repository


def needs_data(dataset: str = "") -> pytest.MarkDecorator:
    """Skip unless the shared dataset folder ``DATA / dataset`` (``DATA`` itself for "") exists."""
    folder = DATA / dataset
    return pytest.mark.skipif(not folder.is_dir(), reason=f"shared measured data not found at {folder}")
