"""Send a job's standard output, standard error and ``logging`` records to its log file.

A bad input found while a job runs (:class:`soilcal.errors.InputError`: a photo that cannot
be read, a table with a bad cell) reaches the user as the same one line that the start-up
validation and the ``soilcal`` command give (``<file>: <field>: expected ..., got ...``): it
is written to the job's log as that line and to the job's real standard error as
``soilcal: error: <line>``, and the job exits with status 2, without a Python traceback.
Any other exception is a fault of soilcal, not of the input: it is logged with its
traceback and re-raised.
"""

from __future__ import annotations

import contextlib
import gc
import logging
import sys
from pathlib import Path


def report_input_error(exc, stream=None) -> None:
    """Print an :class:`~soilcal.errors.InputError` as its one line to ``stream`` (stderr)."""
    stream = sys.stderr if stream is None else stream
    print(f"soilcal: error: {exc}", file=stream, flush=True)


@contextlib.contextmanager
def redirect(log_path: str | Path | None):
    """Redirect stdout/stderr and the root logger to ``log_path`` for the duration.

    An :class:`~soilcal.errors.InputError` raised inside ends the process with status 2
    after one line in the log and one line on the real standard error (module docstring).

    A workflow job script does all its work inside this block, so a block that ends without
    an error ends the job: every object then goes to the garbage collector's permanent
    generation (``gc.freeze``), and the interpreter's exit does not traverse the heap of
    Numba, pandas, SciPy and matplotlib objects once more (a few tenths of a CPU-second per job;
    ``benchmarks/results/job_profile.md``).
    """
    from soilcal.errors import InputError

    if not log_path:
        try:
            yield
        except InputError as exc:
            report_input_error(exc)
            raise SystemExit(2) from None
        gc.freeze()
        return
    Path(log_path).parent.mkdir(parents=True, exist_ok=True)
    real_stderr = sys.stderr
    failed: InputError | None = None
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
                except InputError as exc:
                    logging.getLogger("soilcal").error("%s", exc)
                    failed = exc
                except Exception:
                    logging.getLogger("soilcal").exception("job failed")
                    raise
        finally:
            root.removeHandler(handler)
    if failed is not None:
        report_input_error(failed, real_stderr)
        raise SystemExit(2)
    gc.freeze()


def empty_folder(folder: str | Path, field: str = "folder") -> None:
    """Remove everything in ``folder`` (a run's own output folder, such as the workflow's
    ``logs/<soil>/images/refused``), keeping the folder: files, symlinks (the link, never what it
    points to) and real subfolders with their contents.  ``folder`` may itself be a symlink to a
    folder (kept elsewhere): its target's contents are emptied, the link and its target kept.
    A ``folder`` that does not exist is left so; a path that is no folder is refused."""
    import shutil

    from soilcal.errors import InputError

    folder = Path(folder)
    if not folder.exists() and not folder.is_symlink():
        return
    if not folder.is_dir():
        raise InputError(folder, field, "a folder to empty (or no such path)",
                         "a broken symlink" if folder.is_symlink() else "a file")
    for entry in folder.iterdir():
        if entry.is_symlink() or not entry.is_dir():
            entry.unlink()
        else:
            shutil.rmtree(entry)  # does not follow symlinks inside it
