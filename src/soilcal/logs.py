"""Send a job's standard output, standard error and ``logging`` records to its log file."""

from __future__ import annotations

import contextlib
import logging
from pathlib import Path


@contextlib.contextmanager
def redirect(log_path: str | Path | None):
    """Redirect stdout/stderr and the root logger to ``log_path`` for the duration."""
    if not log_path:
        yield
        return
    Path(log_path).parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "w", encoding="utf-8") as fh:
        handler = logging.StreamHandler(fh)
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
        root = logging.getLogger()
        root.addHandler(handler)
        root.setLevel(logging.INFO)
        try:
            with contextlib.redirect_stdout(fh), contextlib.redirect_stderr(fh):
                try:
                    yield
                except Exception:
                    logging.getLogger("soilcal").exception("job failed")
                    raise
        finally:
            root.removeHandler(handler)
