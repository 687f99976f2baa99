"""Keep Numba's on-disk kernel cache in step with the sources of ``soilcal.dem``.

Numba keys a cached function on the stamp (modification time and size) of its own source
file only.  A kernel that calls or inlines functions of another file (``run_loop`` in
``integrator.py`` calls ``build_lists`` of ``neighbour.py`` and inlines ``contact_force``
of ``contact.py``) keeps their old machine code when only that other file changes, for
example after ``git pull`` in an editable install: the run would silently use the old
physics.  So a digest of every source file of the package is kept beside each cache
directory, and where it differs from the sources the cache files of the package's modules
are removed before any kernel loads; Numba then compiles afresh and caches again.

A lock file beside the cached kernels (:data:`LOCK`, in :func:`cache_dir` of the package) keeps
processes from compiling them side by side: ``soilcal scenario compile`` holds it exclusively
while it compiles (:func:`compiling`), and a process about to call the engine's main kernel for
the first time takes it shared and lets it go at once (:func:`wait_for_compile`): it waits while
a compile is under way, then loads the kernels from the cache.  Where Numba would not cache
(or the system has no ``flock``, Windows) there is no lock.  The lock is ``flock(2)``'s (module :mod:`fcntl`), advisory and released by
the system when its holder ends, even killed.
"""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import sys
import tempfile
from pathlib import Path

STAMP = "soilcal-dem-sources.sha256"
LOCK = "soilcal-dem-kernels.lock"
HERE = Path(__file__).resolve().parent

#: this process holds the lock exclusively (inside :func:`compiling`); two ``open()`` of one
#: file in one process lock against each other, so its own wait must not take the lock
_held = False
#: this process has waited for a compile under way (once per process: from then on the kernels
#: it calls are in memory)
_waited = False


def source_files(root: Path = HERE) -> list[Path]:
    """Every Python source file of the package below ``root``, in a fixed order."""
    return sorted(p for p in root.rglob("*.py") if "__pycache__" not in p.parts)


def source_digest(files) -> str:
    """SHA-256 over the files' names (relative to their common root) and contents."""
    files = sorted(Path(f) for f in files)
    root = Path(os.path.commonpath([str(f.parent) for f in files])) if files else Path(".")
    h = hashlib.sha256()
    for f in files:
        h.update(str(f.relative_to(root)).encode())
        h.update(b"\0")
        h.update(f.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def cache_dir(py_file: Path) -> Path | None:
    """The directory Numba caches the functions of ``py_file`` in (its own locator order:
    NUMBA_CACHE_DIR, then ``__pycache__`` beside the file, then the user-wide cache), or
    None where Numba would not cache."""
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    locators = getattr(impl, "_locator_classes", None)
    if not locators:  # pragma: no cover - a Numba without this internal
        return None

    def probe():
        pass

    for cls in locators:
        try:
            loc = cls.from_function(probe, str(py_file))
        except Exception:  # noqa: BLE001 - a locator that does not apply
            loc = None
        if loc is not None:
            return Path(loc.get_cache_path())
    return None


def refresh(files, dirs_of_files) -> int:
    """Remove the cache files of the modules in ``files`` from every directory in
    ``dirs_of_files`` (a mapping directory -> the files cached there) whose stamp differs
    from the digest of ``files``, then write the stamp.  Returns the number of files
    removed.  Other files in those directories are left alone."""
    digest = source_digest(files)
    removed = 0
    for d, cached in dirs_of_files.items():
        d = Path(d)
        stamp = d / STAMP
        try:
            if stamp.read_text().strip() == digest:
                continue
        except OSError:
            pass
        prefixes = tuple(Path(f).stem + "." for f in cached)
        for f in list(d.glob("*.nbi")) + list(d.glob("*.nbc")):
            if f.name.startswith(prefixes):
                try:
                    f.unlink()
                    removed += 1
                except OSError:
                    pass
        try:
            d.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=d, prefix=STAMP, suffix=".tmp")
            with os.fdopen(fd, "w") as fh:
                fh.write(digest + "\n")
            os.replace(tmp, stamp)
        except OSError:
            pass
    return removed


def refresh_package(root: Path = HERE) -> int:
    """:func:`refresh` for the sources of ``soilcal.dem`` and Numba's cache directories."""
    files = source_files(root)
    by_parent: dict[Path, list[Path]] = {}
    for f in files:
        by_parent.setdefault(f.parent, []).append(f)
    dirs: dict[Path, list[Path]] = {}
    for group in by_parent.values():  # Numba's locators place a directory's files together
        d = cache_dir(group[0])
        if d is not None:
            dirs.setdefault(d, []).extend(group)
    return refresh(files, dirs)


def lock_path(root: Path = HERE) -> Path | None:
    """The lock file of the kernel cache: :data:`LOCK` in the directory Numba caches the
    engine's main kernel (``integrator.run_loop``) in, or None where Numba would not cache or
    the system has no ``flock`` (no module :mod:`fcntl`: Windows), where nothing is locked."""
    try:
        import fcntl  # noqa: F401
    except ImportError:
        return None
    d = cache_dir(root / "integrator.py")
    return None if d is None else d / LOCK


#: errors of open(2) or flock(2) that mean this file system or directory gives no lock
#: (flock not supported: some cluster file systems; a cache directory this user cannot write)
NO_LOCK_ERRNOS = (errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOLCK, errno.EACCES, errno.EPERM, errno.EROFS)


#: lock files this process has warned about (once each)
_warned: set = set()


def _no_lock(path: Path, exc: OSError) -> None:
    if path in _warned:
        return
    _warned.add(path)
    print(f"warning: {path}: the lock of the Numba kernel cache is unavailable ({exc.strerror}): "
          "this process does not wait for a compile under way (soilcal scenario compile); where "
          "one runs, it compiles the kernels itself", file=sys.stderr)


@contextlib.contextmanager
def _locked(path: Path, how: int):
    """``flock`` ``how`` on ``path`` for the ``with`` block (yields True), or, where the file
    system or directory gives no lock (:data:`NO_LOCK_ERRNOS`), a warning on stderr naming the
    file and the reason and no lock (yields False); other errors are raised with the file."""
    import fcntl

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        # read-only: flock needs no write access, so a lock file another user made serves too
        fd = os.open(path, os.O_RDONLY | os.O_CREAT, 0o666)
    except OSError as exc:
        if exc.errno in NO_LOCK_ERRNOS:
            _no_lock(path, exc)
            yield False
            return
        raise OSError(exc.errno, f"{path}: the lock of the Numba kernel cache: expected a file "
                                 f"this process can create or read, got: {exc.strerror}") from None
    try:
        try:
            fcntl.flock(fd, how)
        except OSError as exc:  # BlockingIOError (EAGAIN: held, non-blocking) is raised
            if exc.errno not in NO_LOCK_ERRNOS:
                raise
            _no_lock(path, exc)
            yield False
            return
        yield True
    finally:
        os.close(fd)  # releases the lock


@contextlib.contextmanager
def compiling(root: Path = HERE):
    """Hold the kernel cache's lock exclusively for the ``with`` block (waiting first for any
    other process that holds it): the block compiles the kernels into the cache while other
    processes' :func:`wait_for_compile` waits.  Nothing is locked where :func:`lock_path` is
    None, where the file system gives no lock (a warning says so), or when this process
    already holds the lock."""
    global _held
    path = None if _held else lock_path(root)
    if path is None:
        yield
        return
    import fcntl

    with _locked(path, fcntl.LOCK_EX) as got:
        _held = got
        try:
            yield
        finally:
            _held = False


def wait_for_compile(root: Path = HERE) -> None:
    """Before this process first calls the kernels: wait while another process compiles them
    (holds the lock of :func:`compiling`), by taking the lock shared and releasing it at once.
    Once per process; returns at once in the process that holds the lock, where Numba would
    not cache and where the file system gives no lock (a warning says so)."""
    global _waited
    if _waited or _held:
        return
    path = lock_path(root)
    if path is not None:
        import fcntl

        with _locked(path, fcntl.LOCK_SH):
            pass
    _waited = True


def compile_under_way(root: Path = HERE) -> bool:
    """Whether a process holds the lock of :func:`compiling` (without waiting; True also in
    the holding process itself; False where there is no lock)."""
    path = lock_path(root)
    if path is None:
        return False
    import fcntl

    try:
        with _locked(path, fcntl.LOCK_SH | fcntl.LOCK_NB):
            return False
    except BlockingIOError:
        return True


def kernel_counts() -> dict:
    """How this process got the kernels of ``soilcal.dem`` it called: ``loaded`` from Numba's
    cache or ``compiled`` (no usable cache entry), one count per signature, and the names of
    the compiled ones.  A job that compiled kernels ran before the cache held them (rule
    dem_kernels, ``soilcal scenario compile``) or on a machine the cache was not built for."""
    import sys

    from numba.core.registry import CPUDispatcher

    seen, loaded, compiled, names = set(), 0, 0, []
    for mod_name, mod in list(sys.modules.items()):
        if not mod_name.startswith("soilcal.dem") or mod is None:
            continue
        for obj in list(vars(mod).values()):
            if not isinstance(obj, CPUDispatcher) or id(obj) in seen:
                continue
            seen.add(id(obj))
            stats = obj.stats
            loaded += sum(stats.cache_hits.values())
            missed = sum(stats.cache_misses.values())
            compiled += missed
            if missed:
                names.append(f"{obj.py_func.__module__.rsplit('.', 1)[-1]}.{obj.py_func.__name__}")
    return dict(loaded=loaded, compiled=compiled, names=sorted(names))


def kernel_line() -> str:
    """:func:`kernel_counts` as the line a DEM job prints at its end."""
    c = kernel_counts()
    line = f"Numba kernels: {c['loaded']} loaded from the cache, {c['compiled']} compiled"
    return line + (f" ({', '.join(c['names'])})" if c["names"] else "")
