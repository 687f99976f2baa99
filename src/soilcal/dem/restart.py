"""Restart files of long runs.

A scenario that supports them (``RESTARTABLE = True`` in its module; :func:`supports`) runs its
long stretches through :func:`advance` and :func:`settle` here, which step the engine in chunks
and, every ``every_s`` seconds of wall time, write the whole :class:`~soilcal.dem.engine.
Simulation` and the scenario's own progress (``phase`` and a dict of plain values) to the
restart file.  Started again with the same file, the scenario takes up the saved state and
phase instead of building and filling its simulation anew.  The engine's state is saved whole
(positions, velocities, forces, contact histories, neighbour lists, step count) and its steps
are deterministic, so a resumed run gives the numbers of one uninterrupted run (checked in
tests/dem/test_restart.py); only its wall time differs.

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
    tol = rest_tolerance(sim, rest_speed)
    total = max(1, int(round(max_time / sim.dt)))
    done = int(st.get(key, 0))
    chunk = max(1, CHUNK_STEPS // check_every) * check_every
    stopped = bool(st.get(key + ".stopped", False))
    while done < total and not stopped:
        n = min(chunk, total - done) if checkpoint is not None else total - done
        k = sim.run(n, ke_tol=tol, ke_every=check_every)
        done += k
        # the engine checks the rest at every absolute step that is a multiple of
        # check_every, after the step; a chunk ending on such a step may have ended there
        stopped = k < n or (sim.step % check_every == 0 and sim.kinetic_energy() < tol)
        st[key] = done
        st[key + ".stopped"] = stopped
        if checkpoint is not None and done < total and not stopped:
            checkpoint()
    ok = done < total or sim.kinetic_energy() < tol
    return bool(ok), done * sim.dt
