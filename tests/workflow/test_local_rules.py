"""Which rules run on the submitting host under a cluster executor (``localrules`` in
workflow/rules/common.smk): every rule but the DEM jobs, the rules that declare ``threads:``
(and the default target ``all``), so that a table or a checkpoint that reads a few files is
never queued on the cluster."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _rules() -> dict[str, str]:
    """Every rule and checkpoint of the workflow: name -> its block's text."""
    out = {}
    for path in [ROOT / "Snakefile", *sorted((ROOT / "workflow/rules").glob("*.smk"))]:
        text = path.read_text()
        heads = list(re.finditer(r"^(?:rule|checkpoint) (\w+):", text, flags=re.M))
        for i, m in enumerate(heads):
            end = heads[i + 1].start() if i + 1 < len(heads) else len(text)
            out[m.group(1)] = text[m.start():end]
    return out


def _local() -> set[str]:
    text = (ROOT / "workflow/rules/common.smk").read_text()
    block = re.search(r"^localrules:\n((?:    .*\n)+)", text, flags=re.M).group(1)
    return {r.strip() for r in block.replace("\n", ",").split(",") if r.strip()}


def test_every_rule_but_the_dem_jobs_is_local():
    rules = _rules()
    dem = {name for name, body in rules.items() if re.search(r"^\s+threads:", body, flags=re.M)}
    assert {"dem_point", "verify_point", "refine_point", "tool_point", "loop_point"} <= dem
    assert set(rules) - dem - {"all"} == _local()
