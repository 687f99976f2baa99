"""Restart files of long runs.

A scenario that supports them (``RESTARTABLE = True`` in its module; :func:`supports`; every
scenario of :mod:`soilcal.dem.scenarios`) steps through a :class:`Progress`: its run is a
sequence of named phases (e.g. the drum's ``settle_fill``, ``transient``, ``frames``), its
long stretches go through :func:`advance`, :func:`settle` and :func:`run_to_rest`, which step
the engine in chunks, and every ``every_s`` seconds of wall time the whole
:class:`~soilcal.dem.engine.Simulation` and the scenario's own progress (``phase`` and a dict
of plain values: counters, the series measured so far) go to the restart file.  Started again
with the same file, the scenario takes up the saved state and phase instead of building and
filling its simulation anew.  The engine's state is saved whole (positions, velocities,
forces, contact histories, neighbour lists, wall motions, step count) and its steps are
deterministic, so a resumed run gives the numbers of one uninterrupted run (checked for every
scenario in tests/dem/test_restart.py); only its wall time differs.

File: a pickle of ``{"format", "key", "phase", "vars", "sim", "saved_utc"}``, written to a
temporary file and renamed, so that a kill while writing leaves the previous file whole.  The
key is the SHA-256 of the run's identity: scenario, setup, DEM parameters, preset, seed and
the digest of the engine's sources; a file with another key (another run, or the code changed
since) is not used: the run starts afresh and the log says why.  A finished run removes its
file.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
import time
from datetime import datetime, timezone
from pathlib import Path

from soilcal.errors import InputError

FORMAT = 1
#: steps per engine call between two looks at the clock (a multiple of the rest check's 200)
CHUNK_STEPS = 2000


def supports(module) -> bool:
    """Whether a scenario module writes and reads restart files."""
    return bool(getattr(module, "RESTARTABLE", False))


def identity_key(identity: dict) -> str:
    """SHA-256 of a run's identity (plain values) and of the engine's sources."""
    from soilcal.dem._kernel_cache import source_digest, source_files

    text = json.dumps(identity, sort_keys=True, default=str)
    return hashlib.sha256((text + source_digest(source_files())).encode()).hexdigest()


class Restart:
    """The restart file ``path`` of one run (``identity``: its scenario, setup, parameters,
    preset and seed); written at most every ``every_s`` seconds (0: at every chunk)."""

    def __init__(self, path, identity: dict, every_s: float = 300.0, log=print):
        if not (isinstance(every_s, (int, float)) and not isinstance(every_s, bool)
                and every_s >= 0):
            raise InputError(str(path), "restart_every", "a number of seconds >= 0", every_s)
        self.path = Path(path)
        self.key = identity_key(identity)
        self.every_s = float(every_s)
        self.log = log
        self.saves = 0
        self.resumed_from = None
        self._last = time.monotonic()

    def load(self) -> dict | None:
        """The saved state ({"phase", "vars", "sim"}) of this run, or None (no file, or a
        file of another run or code, which is then left alone and named in the log)."""
        if not self.path.exists():
            return None
        try:
            with open(self.path, "rb") as fh:
                data = pickle.load(fh)
        except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError) as exc:
            self.log(f"restart: {self.path} unreadable ({type(exc).__name__}: {exc}); starting afresh")
            return None
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            self.log(f"restart: {self.path} is not a restart file of this format; starting afresh")
            return None
        if data.get("key") != self.key:
            self.log(f"restart: {self.path} belongs to another run or to other engine sources; "
                     "starting afresh")
            return None
        self.resumed_from = data.get("phase")
        self.log(f"restart: resuming from {self.path} (phase {data['phase']}, step "
                 f"{data['sim'].step}, saved {data.get('saved_utc', '?')})")
        return data

    def due(self) -> bool:
        return time.monotonic() - self._last >= self.every_s

    def save(self, phase: str, sim, vars: dict, force: bool = False) -> bool:
        """Write the file when due (or ``force``); returns whether it wrote."""
        if not (force or self.due()):
            return False
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(self.path.name + ".tmp")
        data = dict(format=FORMAT, key=self.key, phase=phase, vars=vars, sim=sim,
                    saved_utc=datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M:%S"))
        with open(tmp, "wb") as fh:
            pickle.dump(data, fh, protocol=pickle.HIGHEST_PROTOCOL)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, self.path)
        self.saves += 1
        self._last = time.monotonic()
        return True

    def clear(self) -> None:
        """Remove the file (the run finished)."""
        for p in (self.path, self.path.with_name(self.path.name + ".tmp")):
            p.unlink(missing_ok=True)


def advance(sim, steps: int, st: dict, key: str, checkpoint=None) -> int:
    """Run ``steps`` steps, resumably: ``st[key]`` counts the steps done so far.  With
    ``checkpoint`` (a callable that writes the restart file when it is due), the steps go in
    chunks of :data:`CHUNK_STEPS` with a call between two; the same steps as one
    ``sim.run(steps)`` either way.  Returns the steps done in total."""
    done = int(st.get(key, 0))
    steps = int(steps)
    while done < steps:
        n = min(CHUNK_STEPS, steps - done) if checkpoint is not None else steps - done
        done += sim.run(n)
        st[key] = done
        if checkpoint is not None and done < steps:
            checkpoint()
    return done


def settle(sim, rest_speed: float, max_time: float, st: dict, key: str, checkpoint=None,
           check_every: int = 200) -> tuple[bool, float]:
    """:func:`soilcal.dem.scenarios.base.settle`, resumably (``st[key]``: steps done;
    ``checkpoint`` as in :func:`advance`): run until the translational kinetic energy is below
    1/2 M v_rest^2 (checked every ``check_every`` steps) or ``max_time`` seconds have passed;
    returns (settled, simulated seconds)."""
    from soilcal.dem.scenarios.base import rest_tolerance

    if sim.dt is None:
        sim.run(0)
    total = max(1, int(round(max_time / sim.dt)))
    done, ok = run_to_rest(sim, total, rest_tolerance(sim, rest_speed), check_every, st, key,
                           checkpoint)
    return ok, done * sim.dt


def run_to_rest(sim, max_steps: int, ke_tol: float, check_every: int, st: dict, key: str,
                checkpoint=None) -> tuple[int, bool]:
    """``sim.run(max_steps, ke_tol=ke_tol, ke_every=check_every)``, resumably (``st[key]``:
    steps done; ``checkpoint`` as in :func:`advance`): the engine stops once the kinetic
    energy, checked at every step that is a multiple of ``check_every``, is below ``ke_tol``.
    Returns (steps done, whether it came to rest)."""
    total = int(max_steps)
    done = int(st.get(key, 0))
    chunk = max(1, CHUNK_STEPS // check_every) * check_every
    stopped = bool(st.get(key + ".stopped", False))
    while done < total and not stopped:
        n = min(chunk, total - done) if checkpoint is not None else total - done
        k = sim.run(n, ke_tol=ke_tol, ke_every=check_every)
        done += k
        # the engine checks the rest at every absolute step that is a multiple of
        # check_every, after the step; a chunk ending on such a step may have ended there
        stopped = k < n or (sim.step % check_every == 0 and sim.kinetic_energy() < ke_tol)
        st[key] = done
        st[key + ".stopped"] = stopped
        if checkpoint is not None and done < total and not stopped:
            checkpoint()
    return done, bool(done < total or sim.kinetic_energy() < ke_tol)


class Progress:
    """Where a resumable run stands, and the one object its scenario steps through.

    ``phase`` names the stretch the run is in (its scenario's phases, in order); ``vars`` holds
    the run's own plain values (counters, measured series, flags); ``sim`` is the engine.
    :meth:`resume` takes all three from the restart file when it holds this run's state;
    otherwise the scenario builds its simulation and calls :meth:`begin`.  A scenario runs a
    phase's body only when :meth:`at` says the run stands in it, runs its long stretches
    through :meth:`advance` and :meth:`settle` (chunked, with a file written when due), calls
    :meth:`checkpoint` between two short steps of a loop, and :meth:`finish` at its end.
    ``restart=None``: the same calls, no file (and no chunking), so that one code path runs
    with and without restart files.  ``frames``: a :class:`soilcal.dem.scenarios.base.Frames`
    whose list of written frames travels with the file.  The run's wall time (:attr:`wall_s`)
    counts from the object's creation, plus that of earlier sessions."""

    def __init__(self, restart=None, frames=None):
        self.restart = restart
        self._t0 = time.perf_counter()
        self.frames = frames
        self.sim = None
        self.vars: dict = {"phase": None, "wall_s": 0.0}
        self.wall0 = 0.0

    def resume(self) -> bool:
        """Take the saved state of this run, if there is one; returns whether it did."""
        saved = self.restart.load() if self.restart is not None else None
        if not saved:
            return False
        self.sim, self.vars = saved["sim"], saved["vars"]
        self.wall0 = float(self.vars.get("wall_s", 0.0))
        if self.frames is not None:
            self.frames.entries = list(self.vars.get("frames", []))
        return True

    def begin(self, sim, phase: str, **values) -> None:
        """Start (or hand over to a new simulation) at ``phase`` with ``values``."""
        self.sim = sim
        self.vars.update(values)
        self.vars["phase"] = phase

    @property
    def phase(self) -> str | None:
        return self.vars["phase"]

    def at(self, phase: str) -> bool:
        return self.vars["phase"] == phase

    def next(self, phase: str, **values) -> None:
        """Move on to ``phase`` (``values``: the run's values that it starts with)."""
        self.vars.update(values)
        self.vars["phase"] = phase

    @property
    def wall_s(self) -> float:
        """Wall time of the run over every session it took."""
        return self.wall0 + (time.perf_counter() - self._t0)

    def checkpoint(self) -> None:
        """Write the restart file if one is due."""
        if self.restart is None:
            return
        self.vars["wall_s"] = self.wall_s
        if self.frames is not None:
            self.vars["frames"] = list(self.frames.entries)
        self.restart.save(self.vars["phase"], self.sim, self.vars)

    def _saver(self):
        return None if self.restart is None else self.checkpoint

    def advance(self, steps: int, key: str) -> int:
        """:func:`advance` ``steps`` steps of the current phase (``key``: its step counter)."""
        return advance(self.sim, steps, self.vars, key, self._saver())

    def settle(self, rest_speed: float, max_time: float, key: str,
               check_every: int = 200) -> tuple[bool, float]:
        """:func:`settle` in the current phase."""
        return settle(self.sim, rest_speed, max_time, self.vars, key, self._saver(), check_every)

    def run_to_rest(self, max_steps: int, ke_tol: float, check_every: int,
                    key: str) -> tuple[int, bool]:
        """:func:`run_to_rest` in the current phase."""
        return run_to_rest(self.sim, max_steps, ke_tol, check_every, self.vars, key,
                           self._saver())

    def finish(self) -> None:
        """The run is done: remove its file."""
        if self.restart is not None:
            self.restart.clear()
