"""Writing output atomically, and JSON: nothing half-written ever appears at a target path.

- :class:`atomic_output_dir`: a folder is written in a temporary sibling and renamed into place when complete.
- :func:`write_text_atomic`: a single file is written to a temporary sibling and renamed into place.
- :func:`write_json` / :func:`jsonable`: JSON with numpy values as plain numbers and non-finite numbers as null.
- :func:`remove_stale_temporaries`: temporary folders and files carry their writer's pid in their names; those of
  a writer that no longer runs (a killed process) are removed by the next writer in the same folder.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import tempfile
from pathlib import Path

import numpy as np


# ".NAME.tmp-PID-XXXX" (folders of atomic_output_dir), ".NAME.PID.XXXX.tmp" (files of write_text_atomic) and
# ".NAME.old-PID" (a replaced folder on its way out)
_TEMPORARY = re.compile(r"^\..+\.(?:tmp-(?P<dir_pid>\d+)-.*|(?P<file_pid>\d+)\..*\.tmp|old-(?P<old_pid>\d+))$")


def _running(pid: int) -> bool:
    """True if a process with ``pid`` exists (zombies included)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_temporaries(folder: str | Path) -> list[Path]:
    """Remove the temporary folders and files in ``folder`` (not below it) whose writing process is gone.

    Returns the removed paths. Temporaries of running processes (this one included) are left alone.
    """
    folder = Path(folder)
    removed = []
    if not folder.is_dir():
        return removed
    for entry in folder.iterdir():
        match = _TEMPORARY.match(entry.name)
        if not match:
            continue
        pid = int(next(v for v in match.groupdict().values() if v is not None))
        if pid == os.getpid() or _running(pid):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry, ignore_errors=True)
        else:
            entry.unlink(missing_ok=True)
        removed.append(entry)
    return removed


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
        if self.target.exists() and not self.target.is_dir():
            raise FileExistsError(f"{self.target}: exists and is not a folder; name a folder for the output")
        if self.target.exists() and any(self.target.iterdir()) and not self.overwrite:
            raise FileExistsError(f"{self.target}: output folder exists and is not empty "
                                  "(pass overwrite=True / --force)")
        self.target.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(self.target.parent)
        self.tmp = Path(tempfile.mkdtemp(prefix=f".{self.target.name}.tmp-{os.getpid()}-", dir=self.target.parent))
        return self.tmp

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            _replace_dir(self.tmp, self.target)
        else:
            shutil.rmtree(self.tmp, ignore_errors=True)
        return False


def publish_into(tmp: str | Path, target: str | Path) -> None:
    """Move every entry of the finished folder ``tmp`` into ``target`` (created if needed), each replacing an
    entry of the same name, then remove ``tmp``; other entries of ``target`` stay (a shared results folder)."""
    tmp, target = Path(tmp), Path(target)
    target.mkdir(parents=True, exist_ok=True)
    for entry in sorted(tmp.iterdir()):
        destination = target / entry.name
        if entry.is_dir() and destination.is_dir():
            _replace_dir(entry, destination)
        else:
            if destination.is_dir():
                shutil.rmtree(destination)
            os.replace(entry, destination)
    tmp.rmdir()


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder (which must exist), then rename."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent)
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
