"""Files written whole or not at all: a temporary file beside the target, renamed over it, so a
killed job never leaves a partial table that a later run would take for a result."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


@contextlib.contextmanager
def _replacing(path):
    """A temporary file name beside ``path`` (parent folders created), renamed over ``path``
    when the block ends normally and removed when it raises."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (parent folders created)."""
    with _replacing(path) as tmp:
        with open(tmp, "w", newline="") as fh:
            fh.write(text)
    return Path(path)


def copy_file(src, path) -> Path:
    """Copy ``src`` to ``path`` byte for byte, atomically (parent folders created)."""
    import shutil

    with _replacing(path) as tmp:
        shutil.copyfile(src, tmp)
    return Path(path)


__all__ = ["copy_file", "write_text"]
