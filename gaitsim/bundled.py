"""The scenario files shipped with gaitsim: the repository's top-level ``scenarios/`` folder in a source checkout
(or an editable install), else the copy a wheel carries inside the package (``gaitsim/scenarios/``)."""

from __future__ import annotations

from pathlib import Path

PACKAGE = Path(__file__).resolve().parent


def scenario_file(name: str) -> Path:
    """The shipped scenario file ``name`` (e.g. ``"paper.toml"``): the checkout's, else the installed copy.

    Raises
    ------
    FileNotFoundError
        naming both places looked at.
    """
    for folder in (PACKAGE.parent / "scenarios", PACKAGE / "scenarios"):
        if (folder / name).is_file():
            return folder / name
    raise FileNotFoundError(f"scenario {name!r} is in neither {PACKAGE.parent / 'scenarios'} nor "
                            f"{PACKAGE / 'scenarios'}: is the package installed with its scenarios?")
