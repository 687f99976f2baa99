"""A shipped soil's YAML read once and loaded again from an edited copy in a temporary
directory (the config tests' way of trying one change to a real soil)."""

from __future__ import annotations

from pathlib import Path

import yaml

from soilcal.config.load import load_soil, read_yaml

ROOT = Path(__file__).resolve().parents[1]


def read_shipped(soil: str) -> dict:
    """The parsed ``config/soils/<soil>.yaml``."""
    return read_yaml(ROOT / f"config/soils/{soil}.yaml")


def load_copy(tmp_path, soil: str, data: dict):
    """``data`` written as ``<tmp_path>/<soil>.yaml`` and loaded against the shipped resources."""
    p = tmp_path / f"{soil}.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_soil(p, ROOT / "resources")
