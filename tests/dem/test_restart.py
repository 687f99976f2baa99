"""Restart files (soilcal.dem.restart): a run killed after writing one resumes from it and
gives the numbers of the uninterrupted run; a file of another run is not used."""

import pickle

import numpy as np
import pytest

from soilcal.dem import restart as rst
from soilcal.dem.scenarios import repose
from soilcal.dem.scenarios.base import DemParams, run_replicates

SETUP = dict(repose.setups()["cinnamon-soil"], n_particles=300, image=False)
PARAMS = DemParams()
SEED = 3


class Killed(Exception):
    pass


class KillAfter(rst.Restart):
    """A restart file that 'kills' the run right after its k-th write."""

    def __init__(self, path, identity, k):
        super().__init__(path, identity, every_s=0.0, log=lambda *_: None)
        self.k = k

    def save(self, phase, sim, vars, force=False):
        wrote = super().save(phase, sim, vars, force)
        if wrote and self.saves == self.k:
            raise Killed(phase)
        return wrote


def identity(seed=SEED):
    return dict(scenario=repose.NAME, setup=SETUP, params=PARAMS.as_dict(), preset="quick",
                seed=seed)


@pytest.fixture(scope="module", autouse=True)
def short_chunks():
    """Engine calls of 400 steps between looks at the clock, so that the small heap's rest
    phases write several files too."""
    keep = rst.CHUNK_STEPS
    rst.CHUNK_STEPS = 400
    yield
    rst.CHUNK_STEPS = keep


@pytest.fixture(scope="module")
def reference():
    """The uninterrupted run, the same run through the restart path, and the phase of every
    file a run writes at every chance (every_s=0)."""
    plain = repose.run(SETUP, PARAMS, "quick", SEED, threads=1)
    counter = rst.Restart("/nonexistent/never-written", identity(), every_s=0.0)
    phases = []
    counter.save = lambda phase, *a, **k: phases.append(phase) or True
    counted = repose.run(SETUP, PARAMS, "quick", SEED, threads=1, restart=counter)
    return plain, counted, phases


def same(a, b):
    assert a.steps == b.steps and a.n_particles == b.n_particles
    for k, v in a.responses.items():
        w = b.responses[k]
        if isinstance(v, float) and np.isnan(v):
            assert np.isnan(w), k
        else:
            assert w == v, k


def test_chunked_run_equals_the_plain_one(reference):
    plain, counted, phases = reference
    same(plain, counted)
    for phase in ("settle_fill", "lift", "settle_heap"):
        assert phases.count(phase) >= 2, phase


@pytest.mark.parametrize("phase", ["settle_fill", "lift", "settle_heap"])
def test_a_killed_run_resumes_to_the_same_numbers(tmp_path, reference, phase):
    """Killed after the second file written in each phase (inside the fill's rest, between
    two lift steps, inside the heap's rest)."""
    plain, _, phases = reference
    path = tmp_path / "heap.restart"
    k = [i for i, ph in enumerate(phases) if ph == phase][1] + 1
    with pytest.raises(Killed) as exc:
        repose.run(SETUP, PARAMS, "quick", SEED, threads=1,
                   restart=KillAfter(path, identity(), k))
    assert path.exists()
    with open(path, "rb") as fh:
        assert pickle.load(fh)["phase"] == exc.value.args[0]
    logs = []
    again = rst.Restart(path, identity(), every_s=300.0, log=logs.append)
    resumed = repose.run(SETUP, PARAMS, "quick", SEED, threads=1, restart=again)
    assert again.resumed_from == exc.value.args[0] and "resuming" in logs[0]
    same(plain, resumed)
    assert not path.exists()  # a finished run removes its file


def test_a_file_of_another_run_is_not_used(tmp_path, reference):
    path = tmp_path / "heap.restart"
    with pytest.raises(Killed):
        repose.run(SETUP, PARAMS, "quick", SEED + 1, threads=1,
                   restart=KillAfter(path, identity(SEED + 1), 2))
    logs = []
    fresh = repose.run(SETUP, PARAMS, "quick", SEED, threads=1,
                       restart=rst.Restart(path, identity(), log=logs.append))
    assert "another run" in logs[0]
    same(reference[0], fresh)


# every other scenario, each on a case small enough for CI, killed inside each of its phases
def _cases():
    from soilcal.dem.scenarios import bulldozing, compression, drum, furrow, incline, rotary

    dry = DemParams(soil_soil_surface_energy=0.0)
    return {
        "drum": (drum, dict(drum.setups()["xinjiang-vineyard"], n_particles=150, spin_time=0.5,
                            transient_time=0.2, frame_every=0.05), dry, {},
                 ("settle_fill", "transient", "frames")),
        "incline": (incline, dict(incline.setups()["yangtze-static"]), PARAMS, {},
                    ("tilt",)),
        "compression": (compression, dict(compression.setups()["guangxi-cohesive"],
                                          n_particles=200, max_strain=0.1), dry, {},
                        ("settle_fill", "press")),
        "bulldozing": (bulldozing, dict(bulldozing.setups()["plate-line"], travel=0.05,
                                        settle_time=0.1, overrides=["travel", "settle_time"]),
                       bulldozing.paper_params(), dict(use_cache=False), ("bin_0", "pass")),
        "furrow": (furrow, dict(furrow.setups()["yangtze-opener"], travel=0.55, n_slices=1,
                                settle_time=0.1, overrides=["travel", "settle_time", "n_slices"]),
                   furrow.paper_params(), dict(use_cache=False), ("pass",)),
        "rotary": (rotary, dict(rotary.setups()["rpm-250"], travel=0.15, settle_time=0.1,
                                lift_time=0.02, rest_time=0.02,
                                overrides=["travel", "settle_time", "lift_time", "rest_time"]),
                   rotary.paper_params(), dict(use_cache=False), ("bin_1", "lift")),
    }


CASES = _cases()
KILLS = [(name, phase) for name, case in CASES.items() for phase in case[4]]


class Snapshots(rst.Restart):
    """The restart path of a run that goes on to its end: every chance to write a file is
    taken (every_s=0) and its phase listed; at the second chance in each phase of ``kills``
    the file is written as a run killed right after that write would leave it, its bytes
    kept in :attr:`files` (phase -> bytes) and the file removed again."""

    def __init__(self, path, identity, kills):
        super().__init__(path, identity, every_s=0.0, log=lambda *_: None)
        self.kills = kills
        self.phases = []
        self.files = {}

    def save(self, phase, sim, vars, force=False):
        self.phases.append(phase)
        if phase in self.kills and self.phases.count(phase) == 2:
            assert super().save(phase, sim, vars, force=True)
            self.files[phase] = self.path.read_bytes()
            self.clear()
        return True


@pytest.fixture(scope="module")
def references(tmp_path_factory):
    """Per scenario: the uninterrupted run, the same run through the restart path, the
    phase of every file it writes at every chance (every_s=0), and the file it writes at the
    second chance in each phase the tests kill it in (phase -> bytes)."""
    out = {}

    def get(name):
        if name not in out:
            mod, setup, params, kw, kills = CASES[name]
            plain = mod.run(setup, params, "quick", SEED, threads=1, **kw)
            counter = Snapshots(tmp_path_factory.mktemp(name) / "run.restart", _identity(name),
                                kills)
            counted = mod.run(setup, params, "quick", SEED, threads=1, restart=counter, **kw)
            out[name] = plain, counted, counter.phases, counter.files
        return out[name]

    return get


def _identity(name):
    mod, setup, params, _, _ = CASES[name]
    return dict(scenario=mod.NAME, setup=setup, params=params.as_dict(), preset="quick",
                seed=SEED)


@pytest.mark.parametrize("name", list(CASES))
def test_every_scenario_writes_restart_files(name, references):
    mod, kills = CASES[name][0], CASES[name][4]
    plain, counted, phases, files = references(name)
    assert rst.supports(mod)
    same(plain, counted)
    for phase in kills:
        assert phases.count(phase) >= 2, (phase, phases)
    assert set(files) == set(kills)
    for key, v in plain.series.items():
        assert np.array_equal(np.asarray(v), np.asarray(counted.series[key]), equal_nan=True), key


@pytest.mark.parametrize("name,phase", KILLS)
def test_every_scenario_resumes_to_the_same_numbers(tmp_path, references, name, phase):
    """The file a run leaves when killed right after the second file written in the phase
    (the bytes the reference run wrote at that point, :class:`Snapshots`; the repose tests
    above kill the run itself), then the run started again with it: the numbers (responses
    and measured series) of the uninterrupted run."""
    mod, setup, params, kw, _ = CASES[name]
    plain, _, _, files = references(name)
    path = tmp_path / "run.restart"
    path.write_bytes(files[phase])
    with open(path, "rb") as fh:
        assert pickle.load(fh)["phase"] == phase
    again = rst.Restart(path, _identity(name), every_s=300.0, log=lambda *_: None)
    resumed = mod.run(setup, params, "quick", SEED, threads=1, restart=again, **kw)
    assert again.resumed_from == phase
    same(plain, resumed)
    for key, v in plain.series.items():
        assert np.array_equal(np.asarray(v), np.asarray(resumed.series[key]), equal_nan=True), key
    assert not path.exists()


def test_scenarios_without_restart_files_say_so(tmp_path, reference):
    """A scenario whose ``run`` takes no restart file runs without one and the log says so
    (what the run computes is not looked at: the repose run of the module's reference stands
    in for it)."""
    calls = []

    class Plain:
        NAME = "plain"

        @staticmethod
        def run(setup, params, preset, seed, threads, vtk_dir):
            calls.append(seed)
            return reference[0]

    logs = []
    res = run_replicates(Plain, {}, PARAMS, seed=SEED, restart_dir=tmp_path, log=logs.append)
    assert logs == ["restart files: the plain scenario does not write them; it runs from its start"]
    assert calls == [SEED] and res is reference[0] and list(tmp_path.iterdir()) == []
    assert not rst.supports(Plain) and rst.supports(repose)


def test_replicates_keep_one_file_per_seed(tmp_path, reference):
    res = run_replicates(repose, SETUP, PARAMS, seed=SEED, replicates=1, threads=1,
                         restart_dir=tmp_path, restart_every=0.0, log=lambda *_: None)
    same(reference[0], res)
    assert list(tmp_path.iterdir()) == []  # written while it ran, removed at its end


def test_bad_interval_is_named(tmp_path):
    from soilcal.errors import InputError

    with pytest.raises(InputError) as exc:
        rst.Restart(tmp_path / "x", identity(), every_s=-1)
    assert exc.value.field == "restart_every"


def test_a_jobs_restart_folder_follows_its_output():
    from pathlib import Path

    from soilcal.chain.files import restart_dir

    assert restart_dir("results/black-soil/dem/bbd/runs/3.csv") == Path("restart/black-soil/dem/bbd/runs/3")
    assert restart_dir("/w/results/s/dem/verify/paper/bbd/c/1.csv") == Path("restart/s/dem/verify/paper/bbd/c/1")
    assert restart_dir("/w/x.csv") == Path("restart/w/x")


def test_sigkill_then_the_same_command_resumes(tmp_path):
    """The command line: `soilcal scenario run repose ... --restart DIR --restart-every 0`
    killed with SIGKILL once it has written a restart file, then started again, writes the row
    the same command writes uninterrupted (every column but the wall time)."""
    import csv
    import os
    import signal
    import subprocess
    import sys
    import time

    base = [sys.executable, "-m", "soilcal.cli", "scenario", "run", "repose", "--setup",
            "cinnamon-soil", "--set", "n_particles=300", "--set", "image=false", "--seed", "5",
            "--threads", "1"]
    env = dict(os.environ)
    # the uninterrupted row from the same command run in this process (the Numba kernels are
    # loaded already); the killed and the resumed run are commands of their own
    from soilcal.cli import main

    assert main(base[3:] + ["--out", str(tmp_path / "plain.csv")]) == 0
    rdir = tmp_path / "restart"
    cmd = base + ["--out", str(tmp_path / "resumed.csv"), "--restart", str(rdir),
                  "--restart-every", "0"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    t0 = time.monotonic()
    while not list(rdir.glob("*.restart")) and proc.poll() is None and time.monotonic() - t0 < 120:
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it wrote a restart file"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert list(rdir.glob("*.restart")) and not (tmp_path / "resumed.csv").exists()
    out = subprocess.run(cmd, check=True, env=env, capture_output=True, text=True)
    assert "resuming from" in out.stdout
    rows = [list(csv.DictReader(open(tmp_path / f)))[0] for f in ("plain.csv", "resumed.csv")]
    diff = {k for k in rows[0] if rows[0][k] != rows[1].get(k)}
    assert diff == {"wall_s"}
    assert not list(rdir.glob("*.restart"))


def test_a_tool_job_keeps_one_restart_folder_per_spec(tmp_path, monkeypatch):
    """The tool and measured-data-loop jobs (tool_point.py) hand each of their specs its own
    restart folder under the job's, as the design-point jobs do."""
    import pandas as pd

    from soilcal.chain import sources, verify

    seen = []

    def fake(spec, threads=None, restart_dir=None):
        seen.append((spec["seed"], restart_dir))
        return pd.DataFrame([{c: "" for c in sources.RUN_COLUMNS} | {"seed": spec["seed"]}])

    monkeypatch.setattr(sources, "simulate", fake)
    job = {"stage": "bbd", "measurement": "m", "measures": ["x"],
           "specs": [{"seed": 7}, {"seed": 8}]}
    verify.run_tool_point(job, tmp_path / "out.csv", threads=1, restart_dir=tmp_path / "r")
    assert seen == [(7, tmp_path / "r" / "spec0"), (8, tmp_path / "r" / "spec1")]
    verify.run_tool_point(job, tmp_path / "out2.csv", threads=1)
    assert seen[2:] == [(7, None), (8, None)]
