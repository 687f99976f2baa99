"""Every third-party module the package imports is declared in pyproject.toml, and the conda
environment under envs/ pins every declared dependency as pyproject.toml does."""

from __future__ import annotations

import ast
import sys
import tomllib
from importlib.metadata import packages_distributions
from pathlib import Path

import yaml
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def _declared(extra: str | None = None) -> dict[str, Requirement]:
    reqs = PYPROJECT["project"]["dependencies"] if extra is None \
        else PYPROJECT["project"]["optional-dependencies"][extra]
    return {canonicalize_name(r.name): r for r in map(Requirement, reqs)}


def _imported_top_modules() -> set[str]:
    mods: set[str] = set()
    for path in (ROOT / "src" / "soilcal").rglob("*.py"):
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                mods.update(a.name.split(".")[0] for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                mods.add(node.module.split(".")[0])
    return mods - set(sys.stdlib_module_names) - {"soilcal", "__future__"}


def test_every_imported_package_is_declared():
    declared = set(_declared())
    for extra in PYPROJECT["project"].get("optional-dependencies", {}):
        declared |= set(_declared(extra))
    dists = packages_distributions()
    missing = {}
    for mod in sorted(_imported_top_modules()):
        names = {canonicalize_name(d) for d in dists.get(mod, [mod])}
        if not names & declared:
            missing[mod] = sorted(names)
    assert not missing, f"imported by src/soilcal but not declared in pyproject.toml: {missing}"


def _conda_specs() -> dict[str, str]:
    env = yaml.safe_load((ROOT / "envs" / "soilcal.yaml").read_text())
    specs: dict[str, str] = {}
    for dep in env["dependencies"]:
        if isinstance(dep, dict):  # pip: [...]
            for line in dep.get("pip", []):
                line = line.split("#")[0].strip()
                if line and not line.startswith("-"):
                    r = Requirement(line)
                    specs[canonicalize_name(r.name)] = str(r.specifier)
            continue
        cut = next((i for i, ch in enumerate(dep) if ch in "=<>!"), len(dep))
        name, spec = dep[:cut], dep[cut:]
        # conda writes an exact pin with one '=', pip with '=='
        if spec.startswith("=") and not spec.startswith("=="):
            spec = "=" + spec
        specs[canonicalize_name(name.strip())] = spec.strip()
    return specs


def test_conda_environment_matches_pyproject():
    specs = _conda_specs()
    wanted = {**_declared(), **_declared("test")}
    mismatched = {}
    for name, req in wanted.items():
        got = specs.get(name)
        if got is None or {str(s) for s in Requirement(f"x{got}").specifier} != {str(s) for s in req.specifier}:
            mismatched[name] = (str(req.specifier), got)
    assert not mismatched, f"envs/soilcal.yaml differs from pyproject.toml (pyproject, conda): {mismatched}"
