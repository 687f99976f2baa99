"""One chain, two sources: the printed responses fed through the DEM source's gathering give
the same regression, ANOVA, effects and optimum files as the published replay.

For each stage below, the DEM source runs the paper's printed design points
(``simulation.design: printed``), every point's run rows carry the printed response as the
simulated value, and :func:`soilcal.chain.sources.gather_runs` builds the DEM response table.
The DEM stage and the published stage then go through the same writers; the files must be
byte-identical.  (A stage whose reduced model the paper prints by its dropped terms is
reduced that way only for the published source - the DEM source reduces its own data by
backward elimination - so for those stages the full-model rows are compared.)
"""

from __future__ import annotations

import filecmp
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain import derive
from soilcal.chain.plan import dem_context
from soilcal.chain.files import read_stage, write_optimum, write_regression, write_stage_design
from soilcal.chain.sources import RUN_COLUMNS, design_points, gather_runs
from soilcal.chain.targets import targets_frame
from soilcal.config.load import load_soil

ROOT = Path(__file__).resolve().parents[2]

CASES = [("cinnamon-soil", "pb"), ("xinjiang-vineyard", "pb"), ("yangtze-clay-loam", "bbd"),
         ("cinnamon-soil", "steepest")]


def _printed_runs(stage: dict, design: pd.DataFrame, table: pd.DataFrame, columns: dict) -> dict:
    """Run rows whose 'simulated' value is the printed response of the same printed run."""
    runs = {}
    for i, (run, _) in enumerate(design_points(stage, design)):
        rows = []
        for rid, col in columns.items():
            row = {c: "" for c in RUN_COLUMNS}
            row.update(run=run, response=rid, value=float(table[col].iloc[i]), sd=np.nan, n=1, status="ok",
                       error="", seed=0)
            rows.append(row)
        runs[run] = pd.DataFrame(rows, columns=RUN_COLUMNS)
    return runs


@pytest.mark.parametrize("soil_name,stage_id", CASES)
def test_printed_responses_through_the_dem_source_give_the_published_files(tmp_path, soil_name, stage_id):
    soil = load_soil(ROOT / "config/soils" / f"{soil_name}.yaml", ROOT / "resources")
    data = dict(soil.data)
    data["simulation"] = dict(data["simulation"], design="printed")
    config_stage = soil.stage(stage_id)
    table_path = soil.table_path(stage_id)
    table = pd.read_csv(table_path)
    columns = {r["id"]: r.get("column", r["id"]) for r in config_stage["responses"]}

    targets = targets_frame(data, "published")
    tpath = tmp_path / "targets.csv"
    targets.to_csv(tpath, index=False)
    tdict = {r["target_id"]: {"value": None if pd.isna(r["value"]) else float(r["value"])}
             for r in targets.to_dict("records")}

    pub, dem = tmp_path / "published", tmp_path / "dem"
    out = {src: {k: d / f"{k}.csv" for k in ("design", "check")} | {"stage": d / "stage.json"}
           for src, d in (("published", pub), ("dem", dem))}
    write_stage_design("published", config_stage, None, {"table": str(table_path)}, out["published"])
    write_stage_design("dem", config_stage, dem_context(data), {"table": str(table_path), "targets": str(tpath)},
                       out["dem"])
    st_pub, st_dem = read_stage(out["published"]["stage"]), read_stage(out["dem"]["stage"])
    assert st_dem["derivation"]["kind"] == "config"

    design = pd.read_csv(out["dem"]["design"])
    assert len(design) == len(table)
    responses = gather_runs(st_dem, design, _printed_runs(st_dem, design, table, columns))
    responses.to_csv(dem / "responses.csv", index=False)

    names = []
    if config_stage["kind"] != "steepest_ascent":
        names = ["anova", "fit", "coefficients", "effects"]
        for src, st, tab in (("published", st_pub, table_path), ("dem", st_dem, dem / "responses.csv")):
            d = pub if src == "published" else dem
            write_regression(st, tab, {k: d / f"{k}.csv" for k in names})
    if config_stage["kind"] == "steepest_ascent" or config_stage.get("optimise"):
        names += ["optimum", "identifiability"]
        for src, st, tab in (("published", st_pub, table_path), ("dem", st_dem, dem / "responses.csv")):
            d = pub if src == "published" else dem
            write_optimum(st, tab, tdict, soil.data["seed"], d / "optimum.csv", d / "identifiability.csv")
    assert names
    drops = any(pr.get("reduced_drops") for pr in (config_stage.get("printed") or {}).values())
    for n in names:
        if not drops:
            assert filecmp.cmp(pub / f"{n}.csv", dem / f"{n}.csv", shallow=False), n
        elif n in ("anova", "fit", "coefficients", "effects"):
            a, b = pd.read_csv(pub / f"{n}.csv"), pd.read_csv(dem / f"{n}.csv")
            if "model" in a.columns:
                a, b = a[a["model"] == "full"], b[b["model"] == "full"]
            pd.testing.assert_frame_equal(a.reset_index(drop=True), b.reset_index(drop=True), check_exact=True)


def test_a_printed_reduction_is_the_published_source_s_only():
    """The DEM source reduces its own data by backward elimination, never by the paper's drops."""
    soil = load_soil(ROOT / "config/soils/yangtze-clay-loam.yaml", ROOT / "resources")
    st = soil.stage("bbd")
    assert any(pr.get("reduced_drops") for pr in st["printed"].values())
    assert "printed" not in derive.dem_stage(dem_context(soil.data), "bbd", {})
