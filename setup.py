"""Build hook: the wheel carries the top-level ``scenarios/`` as ``gaitsim/scenarios/`` (found by
:mod:`gaitsim.bundled`), so a non-editable install runs ``gaitsim reproduce`` and ``gaitsim fixtures``. Everything
else is declared in pyproject.toml."""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithScenarios(build_py):
    """build_py, then copy scenarios/*.toml into the built package."""

    def run(self):
        super().run()
        target = Path(self.build_lib) / "gaitsim" / "scenarios"
        target.mkdir(parents=True, exist_ok=True)
        for path in sorted(Path(__file__).resolve().parent.joinpath("scenarios").glob("*.toml")):
            shutil.copy2(path, target / path.name)


setup(cmdclass={"build_py": BuildPyWithScenarios})
