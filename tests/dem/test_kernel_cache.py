"""Numba's kernel cache is dropped when any source of soilcal.dem changes (a cached kernel
keeps the machine code of the functions it calls from other files)."""

from pathlib import Path

import pytest

from soilcal.dem import _kernel_cache as kc
from soilcal.dem import contact


def fake_package(tmp_path):
    src = tmp_path / "pkg"
    src.mkdir()
    (src / "integrator.py").write_text("def run_loop(): pass\n")
    (src / "neighbour.py").write_text("def build_lists(): pass\n")
    cache = tmp_path / "cache"
    cache.mkdir()
    for name in ("integrator.run_loop-10.py311.nbi", "integrator.run_loop-10.py311.1.nbc",
                 "neighbour.build_lists-3.py311.nbi", "other.kernel-1.py311.nbi"):
        (cache / name).write_text("x")
    files = kc.source_files(src)
    return src, cache, files


def names(d):
    return sorted(p.name for p in Path(d).iterdir() if p.name != kc.STAMP)


def test_caches_without_a_stamp_are_dropped_and_others_kept(tmp_path):
    src, cache, files = fake_package(tmp_path)
    assert kc.refresh(files, {cache: files}) == 3
    assert names(cache) == ["other.kernel-1.py311.nbi"]
    assert (cache / kc.STAMP).read_text().strip() == kc.source_digest(files)


def test_unchanged_sources_keep_the_cache(tmp_path):
    src, cache, files = fake_package(tmp_path)
    kc.refresh(files, {cache: files})
    (cache / "integrator.run_loop-10.py311.nbi").write_text("fresh")
    assert kc.refresh(files, {cache: files}) == 0
    assert "integrator.run_loop-10.py311.nbi" in names(cache)


def test_a_change_in_a_called_file_drops_the_callers_cache(tmp_path):
    # run_loop's own file is unchanged, but it calls build_lists: its cache must go too
    src, cache, files = fake_package(tmp_path)
    kc.refresh(files, {cache: files})
    (cache / "integrator.run_loop-10.py311.nbi").write_text("old build_lists inside")
    (src / "neighbour.py").write_text("def build_lists(): return 1\n")
    assert kc.refresh(files, {cache: files}) == 1
    assert names(cache) == ["other.kernel-1.py311.nbi"]


def test_cache_dir_is_where_numba_caches_the_kernels():
    # the directory numba's own dispatcher writes jkr_force's cache to
    want = Path(contact.jkr_force._cache._cache_path).resolve()
    assert kc.cache_dir(Path(contact.__file__)).resolve() == want
    assert (want / kc.STAMP).read_text().strip() == kc.source_digest(kc.source_files())


def test_a_job_says_whether_it_compiled_or_loaded_its_kernels(tmp_path):
    """kernel_counts: the first process to call a kernel with an empty cache compiles it, the
    next one loads it (the line every DEM job of the workflow ends its log with)."""
    import os
    import subprocess
    import sys

    code = ("from soilcal.dem import contact, _kernel_cache as kc; "
            "contact.jkr_root(1e-6, 1e-3, 0.05, 0.0); print(kc.kernel_line())")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    first, second = (subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                    text=True, check=True).stdout.strip() for _ in range(2))
    assert first == "Numba kernels: 0 loaded from the cache, 1 compiled (contact.jkr_root)"
    assert second == "Numba kernels: 1 loaded from the cache, 0 compiled"


# a few-sphere DEM run (two spheres falling onto a plane): its first call of the engine's time
# loop is where a process waits for a compile under way
FEW_SPHERES = """
import sys, time
from soilcal.dem.engine import Simulation
from soilcal.dem.materials import Material, MaterialTable
mats = MaterialTable()
mats.add(Material("soil", 2600.0, 0.3, youngs=1e7))
mats.set_pair("soil", "soil", 0.5, 0.5, 0.0, 0.0, 0.0)
sim = Simulation(mats, dt_fraction=0.2)
sim.add_particles([[0, 0, 0.006], [0.02, 0, 0.006]], 5e-3, "soil")
sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
sim.run(50)
open(sys.argv[1], "w").write(repr(time.time_ns()))
"""

# holds the kernel cache's lock as `soilcal scenario compile` does, until a process waits on it
# (a blocked lock on the file in /proc/locks) or the run has ended without waiting (its file
# exists); writes the time it lets the lock go
HOLDER = """
import os, sys, time
from soilcal.dem import _kernel_cache as kc
released, run_done, held = sys.argv[1:4]
with kc.compiling():
    open(held, "w").write("held")
    ino = os.stat(kc.lock_path()).st_ino
    def waited_on():
        with open("/proc/locks") as f:
            return any("->" in ln and ln.split()[-3].endswith(f":{ino}") for ln in f)
    t_end = time.monotonic() + 900
    while not (os.path.exists(run_done) or waited_on()) and time.monotonic() < t_end:
        time.sleep(0.05)
    open(released, "w").write(repr(time.time_ns()))
"""


def _python(code, *args, **kw):
    import subprocess
    import sys

    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)], **kw)


@pytest.mark.skipif(not Path("/proc/locks").exists(), reason="needs Linux's /proc/locks")
def test_a_run_waits_for_a_compile_under_way_then_loads(tmp_path):
    """A process that reaches the time loop while another holds the kernel cache's lock
    (soilcal scenario compile) finishes only after the holder let it go."""
    import time

    released, run_done, held = (tmp_path / n for n in ("released", "run_done", "held"))
    holder = _python(HOLDER, released, run_done, held)
    try:
        t_end = time.monotonic() + 1200  # a compile under way (CI's) holds the lock first
        while not held.exists():
            assert holder.poll() is None, "the lock holder ended before it took the lock"
            assert time.monotonic() < t_end, "the lock holder did not take the lock"
            time.sleep(0.05)
        run = _python(FEW_SPHERES, run_done)
        assert run.wait(timeout=1200) == 0
        assert holder.wait(timeout=60) == 0
    finally:
        holder.kill()
    assert int(run_done.read_text()) > int(released.read_text())


@pytest.mark.skipif(not Path("/proc/locks").exists(), reason="needs Linux's /proc/locks")
def test_the_compiling_process_does_not_wait_on_its_own_lock(tmp_path):
    """Inside kc.compiling() (what soilcal scenario compile runs in) the engine's wait for a
    compile under way returns at once: two open() of one file lock against each other even
    in one process."""
    code = ("import sys; from soilcal.dem import _kernel_cache as kc\n"
            "with kc.compiling():\n"
            "    assert kc.compile_under_way()\n"
            "    WATCHDOG\n"
            + "".join("    " + ln + "\n" for ln in FEW_SPHERES.strip().splitlines()))
    run = _python(code.replace("WATCHDOG", SELF_WAIT_WATCHDOG), tmp_path / "done")
    try:
        # entering compiling() may wait for a compile under way elsewhere (CI's); a wait on
        # its own lock ends the process with 3 within a second
        rc = run.wait(timeout=1200)
    finally:
        run.kill()
    assert rc != 3, "the compiling process waited on its own lock"
    assert rc == 0
    assert (tmp_path / "done").exists()


# inside kc.compiling(): a thread that ends the process with 3 as soon as /proc/locks shows
# this process blocked on the kernel cache's lock file (a wait on its own lock never ends)
SELF_WAIT_WATCHDOG = (
    "import os, threading, time; ino = os.stat(kc.lock_path()).st_ino; pid = str(os.getpid())\n"
    "    def _watch():\n"
    "        while True:\n"
    "            with open('/proc/locks') as f:\n"
    "                if any('->' in ln and ln.split()[-4] == pid\n"
    "                       and ln.split()[-3].endswith(f':{ino}') for ln in f):\n"
    "                    os._exit(3)\n"
    "            time.sleep(0.05)\n"
    "    threading.Thread(target=_watch, daemon=True).start()")


@pytest.mark.parametrize("err", ["ENOSYS", "EOPNOTSUPP", "ENOLCK"])
def test_a_file_system_without_flock_gives_no_lock_and_says_so(tmp_path, monkeypatch, capsys, err):
    """A cache on a file system without flock (some cluster file systems): the DEM process
    neither fails nor waits; one warning per lock file names it and the reason."""
    import errno
    import fcntl
    import os

    def no_flock(fd, how):
        raise OSError(getattr(errno, err), os.strerror(getattr(errno, err)))

    lock = tmp_path / kc.LOCK
    monkeypatch.setattr(kc, "lock_path", lambda root=kc.HERE: lock)
    monkeypatch.setattr(fcntl, "flock", no_flock)
    monkeypatch.setattr(kc, "_waited", False)
    monkeypatch.setattr(kc, "_warned", set())
    kc.wait_for_compile()
    assert kc._waited
    with kc.compiling():
        assert not kc._held  # no lock taken: its own wait must not be skipped for a lock it lacks
    assert not kc.compile_under_way()
    err_text = capsys.readouterr().err
    assert err_text.count("warning:") == 1 and str(lock) in err_text
    assert os.strerror(getattr(errno, err)) in err_text


def test_another_flock_error_is_raised_with_the_file(tmp_path, monkeypatch):
    import errno
    import fcntl

    def broken(fd, how):
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(kc, "lock_path", lambda root=kc.HERE: tmp_path / kc.LOCK)
    monkeypatch.setattr(fcntl, "flock", broken)
    monkeypatch.setattr(kc, "_waited", False)
    with pytest.raises(OSError, match="Input/output error"):
        kc.wait_for_compile()
    assert not kc._waited


def test_a_lock_held_elsewhere_is_seen_without_waiting(tmp_path, monkeypatch):
    """compile_under_way: True while another open file description holds the lock
    exclusively (as another process's compile does), False once it is let go."""
    import fcntl
    import os

    lock = tmp_path / kc.LOCK
    monkeypatch.setattr(kc, "lock_path", lambda root=kc.HERE: lock)
    assert not kc.compile_under_way()
    fd = os.open(lock, os.O_RDONLY | os.O_CREAT, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        assert kc.compile_under_way()
    finally:
        os.close(fd)
    assert not kc.compile_under_way()
