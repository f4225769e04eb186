"""How numbers are written into reports and tables: one formatter for every table the project writes."""

from __future__ import annotations

import math


def shown(x, spec: str = ".4g") -> str:
    """``x`` written with the format ``spec`` (default 4 significant digits); "-" for a missing (None) or
    non-finite number; text and integers as they are."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    if isinstance(x, float):
        return f"{x:{spec}}"
    return str(x)
