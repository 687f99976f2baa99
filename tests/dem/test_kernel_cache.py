"""Numba's kernel cache is dropped when any source of soilcal.dem changes (a cached kernel
keeps the machine code of the functions it calls from other files)."""

from pathlib import Path

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
