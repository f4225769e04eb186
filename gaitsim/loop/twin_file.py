"""The fitted twin as a scenario file (``twin.toml``) that ``gaitsim generate`` reads back to the same scenario.

Scenario documents (:func:`gaitsim.scenario.scenario_document`) hold tables of numbers, strings, booleans and
(nested) lists, values with units as ``[value, "unit"]`` pairs; that is all :func:`toml_text` writes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..scenario import scenario_document


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if math.isnan(v) else ("inf" if v > 0 else "-inf"))
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"twin.toml: cannot write a value of type {type(v).__name__} ({v!r})")


def toml_text(doc: dict) -> str:
    """TOML text of a scenario document: one ``[section]`` per table (sub-tables as ``[section.name]``)."""
    lines = []

    def table(name: str, items: dict) -> None:
        scalars = {k: v for k, v in items.items() if not isinstance(v, dict)}
        lines.extend([f"[{name}]"] + [f"{k} = {_value(v)}" for k, v in scalars.items() if v is not None] + [""])
        for key, sub in items.items():
            if isinstance(sub, dict):
                table(f"{name}.{key}", sub)

    for section, items in doc.items():
        table(section, items)
    return "\n".join(lines)


def write_twin_toml(scenario, path: Path, comment: str) -> None:
    """Write ``scenario`` as TOML to ``path``, headed by ``comment`` lines."""
    header = "".join(f"# {line}\n" for line in comment.splitlines())
    Path(path).write_text(header + "\n" + toml_text(scenario_document(scenario)))
