"""A copy of the workflow (Snakefile, rules, config, chosen soils' resources) in a temporary
directory, and snakemake runs in it."""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


def copy_soil(tmp: Path, soil: str = "cinnamon-soil") -> Path:
    """A shipped soil's YAML and its resources under ``tmp``; returns the YAML path."""
    (tmp / "config/soils").mkdir(parents=True, exist_ok=True)
    dst = tmp / "config/soils" / f"{soil}.yaml"
    shutil.copy(ROOT / "config/soils" / f"{soil}.yaml", dst)
    for kind in ("published", "measurements", "images", "geometry"):
        src = ROOT / "resources" / kind / soil
        if src.is_dir():
            shutil.copytree(src, tmp / "resources" / kind / soil)
    return dst


def copy_workflow(tmp: Path, soils: list[str], source: str | None = None) -> Path:
    shutil.copy(ROOT / "Snakefile", tmp / "Snakefile")
    shutil.copytree(ROOT / "envs", tmp / "envs")
    for item in ("workflow", "config", "profiles"):
        shutil.copytree(ROOT / item, tmp / item, symlinks=True)
    # the schema symlinks point into the package; resolve them for the copy
    for name, target in (("soil", "soil"), ("config", "workflow")):
        link = tmp / f"workflow/schemas/{name}.schema.yaml"
        if link.is_symlink():
            link.unlink()
            shutil.copy(ROOT / f"src/soilcal/config/{target}.schema.yaml", link)
    for soil in soils:
        for kind in ("published", "measurements", "images", "geometry"):
            if (ROOT / "resources" / kind / soil).is_dir():
                shutil.copytree(ROOT / "resources" / kind / soil, tmp / "resources" / kind / soil)
    cfg = yaml.safe_load((tmp / "config/config.yaml").read_text())
    cfg["soils"] = soils
    if source:
        cfg["source"] = source
    (tmp / "config/config.yaml").write_text(yaml.safe_dump(cfg))
    return tmp


def adaptive_soil(tmp: Path, soil: str, response: str, n_spheres: int, budget: int, setup: dict | None = None,
                  photos: bool = True, printed_targets: bool = False, **settings) -> Path:
    """Set up ``soil`` of a workflow copy (``copy_workflow``) for design: adaptive: its
    ``response`` simulated with ``n_spheres`` spheres (and further ``setup`` values) and a
    ``budget`` of runs per case (and further ``simulation.adaptive`` settings).
    ``photos=False``: without the soil's photos (for a soil whose targets read none of them: no
    job measures photos nothing reads).  ``printed_targets=True``: every target takes its
    printed value, none reads a photo group."""
    p = tmp / f"config/soils/{soil}.yaml"
    d = yaml.safe_load(p.read_text())
    if printed_targets:
        for t in d["targets"].values():
            t.pop("image", None)
    if not photos:
        read = sorted(t["image"] for t in d["targets"].values() if t.get("image"))
        if read:
            raise ValueError(f"{soil}: targets read the photo groups {read}: keep its photos")
        shutil.rmtree(tmp / "resources/images" / soil, ignore_errors=True)
    # the copy's set replaces the soil's whole: a setting the soil ships there (the cohesive
    # soil's read_time) is dropped unless ``setup`` gives it, so its heaps are read at the rest
    # rule, which keeps these fixtures' DEM time what it was
    d["simulation"]["responses"][response]["set"] = {"n_particles": n_spheres, **(setup or {})}
    d["simulation"]["adaptive"] = {"budget": budget, **settings}
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return tmp


#: the Snakemake default's re-planning interval (profiles/default sets ten seconds, which a run
#: waits out at its end: a test's short runs would wait it out every time)
PASS_INTERVAL = ["--max-jobs-per-timespan", "100/1s"]


def run(tmp: Path, *args, check=True):
    p = subprocess.run(SNAKEMAKE + PASS_INTERVAL + list(args), cwd=tmp, capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(p.stdout[-4000:] + p.stderr[-4000:])
    return p


#: the jobs a dry run planned, by the state of the workflow copy it ran in and its arguments
#: (``planned_jobs``)
_PLANNED: dict[str, list[str]] = {}


def tree_state(tmp: Path) -> str:
    """SHA-256 over every entry below ``tmp``: its path, kind, and for a file its size,
    modification time (ns) and contents, for a symlink its target.  Left out: what Snakemake
    writes on every call and does not read back unasked, its logs (``.snakemake/log``) and the
    file a dry run saves its file listing to (``.snakemake/iocache``, read only with
    ``--trust-io-cache``); everything else a dry run reads (the Snakefile, rules, config,
    inputs, outputs and their times, Snakemake's metadata) is in."""
    h = hashlib.sha256()
    for root, dirs, files in os.walk(tmp):
        rel = Path(root).relative_to(tmp)
        if rel == Path(".snakemake"):
            dirs[:] = [d for d in dirs if d not in ("log", "iocache")]
        dirs.sort()
        for name in sorted(dirs) + sorted(files):
            p = Path(root) / name
            h.update(str(rel / name).encode() + b"\0")
            if p.is_symlink():
                h.update(b"L" + os.readlink(p).encode())
            elif p.is_dir():
                h.update(b"D")
            else:
                st = p.stat()
                h.update(b"F%d:%d:" % (st.st_size, st.st_mtime_ns))
                h.update(hashlib.sha256(p.read_bytes()).digest())
            h.update(b"\0")
    return h.hexdigest()


def planned_jobs(tmp: Path, *args) -> list[str]:
    """The outputs of the jobs ``snakemake -n`` plans in the copy ``tmp``.  A dry run changes
    nothing in the copy, so two tests asking of the same state (``tree_state``) with the same
    arguments get the one dry run's answer (a test that restores the files it edited asks
    again of the state a test before it asked of)."""
    key = hashlib.sha256(repr((str(tmp), args, tree_state(tmp))).encode()).hexdigest()
    if key not in _PLANNED:
        out = run(tmp, "-n", "--cores", "2", *args).stdout
        _PLANNED[key] = re.findall(r"^\s+output: (.+)$", out, flags=re.M)
    return list(_PLANNED[key])


#: The soil of the tiny run: the cinnamon soil, calibrated on the DEM and replayed from its
#: printed tables.
TINY_SOILS = ["cinnamon-soil"]
#: The second soil of the session's tiny run (tests/workflow/conftest.py): replayed from its
#: printed tables only, beside the cinnamon soil, so that the run replays two soils and an edit
#: of one soil can be seen to re-run that soil alone (``replay_only``).
REPLAY_SOIL = "yangtze-clay-loam"
#: Spheres per heap of the tiny run.
N_SPHERES = 300
#: Cylinder lift speed (m/s) of the tiny run's heaps: four times the paper's 0.05 m/s, so that
#: the lift takes a quarter of the steps (the tests read the stages' files, seeds and wiring,
#: not the angles' values).
LIFT_SPEED = 0.2
#: Plate speed (m/s) of the tiny run's soil-bin passes: four times the paper's 0.16 m/s, so that
#: the preset's 0.2 m pass takes a quarter of the steps.
TOOL_SPEED = 0.64


def make_tiny(tmp: Path, threads: int | None = None) -> Path:
    """Turn a workflow copy into the tiny run: heaps of ``N_SPHERES`` spheres lifted at
    ``LIFT_SPEED`` and measured in two side views, two verification seeds, one seed per measured
    plate driven at ``TOOL_SPEED`` (its pass a quarter of the quick preset's steps; the tests
    read the forces' rows, seeds and residuals, not their values), and the measured-data loop trying the adhesion effect at three
    levels whatever the diagnosis says; ``threads``: the DEM jobs' Numba threads (the soil's
    ``simulation.threads``)."""
    p = tmp / "config/soils/cinnamon-soil.yaml"
    d = yaml.safe_load(p.read_text())
    d["source"] = "both"
    d["simulation"]["responses"]["stacking_angle"]["set"] = {"n_particles": N_SPHERES, "image_views": 2,
                                                              "lift_speed": LIFT_SPEED}
    d["simulation"]["verification"] = {"replicates": 2}
    if threads is not None:
        d["simulation"]["threads"] = int(threads)
    for m in d.get("measurements", {}).values():
        m["replicates"] = 1
    d["measurements"]["cutting_resistance"]["set"] = {"speed": TOOL_SPEED}
    d["loop"] = {"candidates": "all", "effects": ["tool_adhesion"], "design_points": 3}
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return tmp


def replay_only(tmp: Path, soil: str = REPLAY_SOIL) -> Path:
    """Have a workflow copy replay ``soil`` from its printed tables only (its ``source:
    published``) and leave out its photos: no target of the published source reads them, so no
    job measures them."""
    p = tmp / f"config/soils/{soil}.yaml"
    d = yaml.safe_load(p.read_text())
    d["source"] = "published"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    shutil.rmtree(tmp / "resources/images" / soil, ignore_errors=True)
    return tmp
