"""Writing output atomically, and JSON: nothing half-written ever appears at a target path.

- :class:`atomic_output_dir`: a folder is written in a temporary sibling and renamed into place when complete.
- :func:`write_text_atomic`: a single file is written to a temporary sibling and renamed into place.
- :func:`write_json` / :func:`jsonable`: JSON with numpy values as plain numbers and non-finite numbers as null.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np


def _replace_dir(tmp: Path, target: Path) -> None:
    """Move a finished temporary folder into place; an older ``target`` is replaced only now."""
    if target.exists():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        os.replace(target, old)
        os.replace(tmp, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(tmp, target)


class atomic_output_dir:
    """``with atomic_output_dir(DIR) as tmp:`` write into ``tmp``; it becomes DIR only if the block succeeds.

    Parameters
    ----------
    target : the output folder; its parent is created if needed.
    overwrite : replace an existing non-empty ``target`` (when the block succeeds); else raise FileExistsError.
    """

    def __init__(self, target: str | Path, overwrite: bool = False):
        self.target = Path(target)
        self.overwrite = overwrite

    def __enter__(self) -> Path:
        if self.target.exists() and any(self.target.iterdir()) and not self.overwrite:
            raise FileExistsError(f"{self.target}: output folder exists and is not empty "
                                  "(pass overwrite=True / --force)")
        self.target.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = Path(tempfile.mkdtemp(prefix=f".{self.target.name}.tmp-", dir=self.target.parent))
        return self.tmp

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            _replace_dir(self.tmp, self.target)
        else:
            shutil.rmtree(self.tmp, ignore_errors=True)
        return False


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder (which must exist), then rename."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    return path


def jsonable(o):
    """JSON-ready copy: numpy to Python, non-finite floats to None."""
    if isinstance(o, dict):
        return {str(k): jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return jsonable(o.tolist())
    if isinstance(o, (np.floating, float)):
        return None if not math.isfinite(float(o)) else float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, np.bool_):
        return bool(o)
    return o


def write_json(path: str | Path, doc: dict) -> Path:
    """Write ``doc`` as indented JSON with sorted keys (see :func:`jsonable`), atomically."""
    return write_text_atomic(path, json.dumps(jsonable(doc), indent=2, sort_keys=True))
