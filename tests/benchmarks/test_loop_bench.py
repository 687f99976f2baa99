"""The loop benchmark's DEM campaign speeds (uniform in v or in ln v over 0.1-1.0 m/s, from the
same uniform draw) and its rows' spacing: a campaign of one spacing neither replaces nor is
counted with the other's; the header's file labels; a rerun campaign's tables replace the
earlier run's, a table the rerun does not make included."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("loop.py", "loop_bench")


@pytest.mark.parametrize("seed", [0, 7])
def test_campaign_speed_maps_one_draw(bench, seed):
    # the generator's first standard-uniform draw u; uniform in [0.1, 1.0): 0.1 + 0.9 u;
    # uniform in ln v over the same range: exp(ln 0.1 + u (ln 1 - ln 0.1)) = 0.1 * 10**u
    u = np.random.default_rng(seed).random()
    assert bench.campaign_speed(np.random.default_rng(seed), "uniform") == pytest.approx(0.1 + 0.9 * u, rel=1e-12)
    assert bench.campaign_speed(np.random.default_rng(seed), "log") == pytest.approx(0.1 * 10 ** u, rel=1e-12)


def test_campaign_speed_refuses_an_unknown_spacing(bench):
    with pytest.raises(ValueError, match="'Log' is not one of log, uniform"):
        bench.campaign_speed(np.random.default_rng(0), "Log")


def _row(case, seed, speeds, before="20", engine="dem"):
    return {"engine": engine, "case": case, "seed": seed, "speeds": speeds, "correct": "True",
            "false_attribution": "False", "parameter_error_percent": "", "rmse_before_percent": before,
            "rmse_after_percent": before, "wall_s": "1"}


def test_speeds_column(bench):
    assert bench._speeds_text(_row("none", 0, "log")) == "log"
    assert bench._speeds_text(_row("none", 0, "")) == "uniform"  # written before the column existed
    assert bench._speeds_text(_row("plastic_contact", 0, "")) == ""  # a compression campaign
    assert bench._speeds_text(_row("none", 0, "", engine="standin")) == ""


def test_a_campaign_of_the_other_spacing_replaces_nothing(bench):
    old_uniform, old_log = _row("none", 0, ""), _row("none", 0, "log")
    assert not bench.replaced(old_uniform, [_row("none", 0, "log")])
    assert bench.replaced(old_log, [_row("none", 0, "log")])
    assert bench.replaced(old_uniform, [_row("none", 0, "uniform")])
    assert not bench.replaced(old_log, [_row("none", 1, "log")])
    # a stand-in case reruns all its seeds, whatever their number
    assert bench.replaced(_row("none", 3, "", engine="standin"), [_row("none", 0, "", engine="standin")])


def test_summary_counts_the_spacings_apart(bench):
    rows = [_row("none", 0, "", "10"), _row("none", 1, "uniform", "12"), _row("none", 0, "log", "30"),
            _row("stones", 0, "")]
    lines = bench._summary(rows)[2:]
    assert lines == ["| dem | none (uniform speeds) | 2 | 2 | 0 |  | 11.00 -> 11.00 |  |  | 1.0 |",
                     "| dem | none (log speeds) | 1 | 1 | 0 |  | 30.00 -> 30.00 |  |  | 1.0 |",
                     "| dem | stones | 1 | 1 | 0 |  | 20.00 -> 20.00 |  |  | 1.0 |"]


def test_summary_gives_each_campaigns_floor_and_how_many_rows_have_one(bench):
    # two of three campaigns with a floor, of 9.5 and 8.5: their median 9.0 would match neither
    rows = [dict(_row("none", 0, "log", "10"), rmse_floor_percent="9.5", explained_percent=""),
            dict(_row("none", 1, "log", "12"), rmse_floor_percent="8.5", explained_percent="40"),
            dict(_row("none", 2, "log", "14"), rmse_floor_percent="", explained_percent="")]
    assert bench._summary(rows)[2:] == ["| dem | none | 3 | 3 | 0 |  | 12.00 -> 12.00 | 8.50, 9.50 (2 of 3) | "
                                        "40 (1 of 3) | 1.0 |"]
    # explained shares of 0 and 112.2: both shown, not "56"
    rows[0]["explained_percent"], rows[1]["explained_percent"] = "112.2", "0.0"
    assert "| 0, 112 (2 of 3) |" in bench._summary(rows)[2]


def test_summary_gives_the_median_and_range_of_more_campaigns(bench):
    # five campaigns: floors 1.0-1.4, median 1.3; shares 90-101, median 99
    rows = [dict(_row("none", i, "log", "10"), rmse_floor_percent=f, explained_percent=e)
            for i, (f, e) in enumerate([("1.3", "99.4"), ("1.0", "90.0"), ("1.4", "101.0"), ("1.2", "98.6"),
                                        ("1.35", "100.0")])]
    assert bench._summary(rows)[2].split(" | ")[7:9] == ["1.30 (1.00 to 1.40)", "99 (90 to 101)"]


def test_an_earlier_dem_row_takes_its_floor_from_its_campaign_tables(bench, tmp_path):
    # a campaign's saved residual table: 100 N measured (SD 10 N over 4 repeats) against 90 N
    # simulated (SD 6 N over 3 seeds), 200 N (SD 20 N, 4) against 210 N (SD 12 N, 3); relative
    # residuals 0.1 and -0.05, so the RMS error sqrt((0.01 + 0.0025) / 2) = 7.91 %; each row's
    # floor term (10^2 / 4 + 6^2 / 3) / 100^2 = (20^2 / 4 + 12^2 / 3) / 200^2 = 0.0037, so the
    # floor sqrt(0.0037) = 6.08 %; nothing chosen, no held-out predictions: after = before
    import pandas as pd

    detail = tmp_path / "loop_dem"
    detail.mkdir()
    pd.DataFrame({"measurement": "campaign", "row": [1, 2], "measure": "horizontal_force_N",
                  "simulation": ["a", "b"], "measured": [100.0, 200.0], "measured_sd": [10.0, 20.0],
                  "measured_n": [4.0, 4.0], "simulated_mean": [90.0, 210.0], "simulated_sd": [6.0, 12.0],
                  "simulated_n": [3, 3], "scale": [100.0, 200.0], "relative_residual": [0.1, -0.05]}
                 ).to_csv(detail / "none_campaign1_residuals.csv", index=False)
    row = dict(_row("none", 1, "log", "7.91"), responses="")
    assert bench.detail_tag(row) == "none_campaign1"
    # the floor's 95 % interval (two rows, each SD on 2-3 degrees of freedom) reaches above the
    # 7.91 % before: no explainable part told apart from the floor's uncertainty, no share
    from soilcal.loop import residuals as rs

    assert rs.floor_interval(rs.usable(pd.read_csv(detail / "none_campaign1_residuals.csv")))[1] > 0.0791
    assert bench.floor_of(row, detail) == (6.08, "")
    # tables that do not give the row's errors are another run's: no floor from them
    assert bench.floor_of(dict(row, rmse_before_percent="8.00", rmse_after_percent="8.00"), detail) == ("", "")
    assert bench.floor_of(dict(row, seed=2), detail) == ("", "")  # no tables of that campaign
    # a row with its own floor keeps it
    assert bench.floor_of(dict(row, rmse_floor_percent="5.5", explained_percent="12.0"), detail) == ("5.5", "12.0")
    # a row of this run (numbers, not text): an explained share of 0 is 0, not empty
    assert bench.floor_of(dict(row, engine="standin", rmse_floor_percent=1.42, explained_percent=0.0), detail) == (
        "1.42", "0.0")


def test_header_names_files_not_directories(bench):
    text = bench._command_text(["--engines", "none", "--rows-from", "/scratch/a/rate.csv",
                                "--rows-from=/scratch/b/none.csv", "--out", "/scratch/c/out"])
    assert text == "--engines none --rows-from rate.csv --rows-from none.csv --out out"


def test_header_tells_two_files_of_one_name_apart(bench):
    # two runs' tables of the same name: each named with the directory that tells it apart
    text = bench._command_text(["--engines", "none", "--rows-from", "/scratch/out/rate/loop.csv",
                                "--rows-from", "/scratch/out/none/loop.csv"])
    assert text == "--engines none --rows-from rate/loop.csv --rows-from none/loop.csv"
    assert bench.source_labels(["/s/x/a/loop.csv", "/s/y/a/loop.csv", "/s/y/b.csv"]) == [
        "x/a/loop.csv", "y/a/loop.csv", "b.csv"]


def test_a_file_given_twice_is_refused(bench, tmp_path):
    with pytest.raises(ValueError, match="given twice"):
        bench.source_labels([tmp_path / "loop.csv", tmp_path / "sub" / ".." / "loop.csv"])
    with pytest.raises(SystemExit):
        bench.main(["--engines", "none", "--out", str(tmp_path / "out"),
                    "--rows-from", str(tmp_path / "loop.csv"), "--rows-from", str(tmp_path / "loop.csv")])
    assert not (tmp_path / "out").exists()  # refused before anything is written


def test_header_names_the_merged_rows(bench):
    assert bench._merged_text([]) == ""
    assert bench._merged_text([("rate/loop.csv", [_row("none", 0, "log"), _row("stones", 1, "")]),
                               ("none/loop.csv", [_row("plastic_contact", 0, ""), _row("none", 2, "", engine="standin")]),
                               ("empty.csv", [])]) == (
        "; rows taken from other runs: rate/loop.csv: dem none campaign 0 (log speeds), dem stones campaign 1 "
        "(uniform speeds); none/loop.csv: dem plastic_contact campaign 0, standin none seed 2; empty.csv: no rows")


def _no_dem_loop(bench, monkeypatch, campaign):
    """dem_rows without the DEM: ``campaign`` stands for ``_campaign``, and the loop's outcome
    is one where nothing is chosen (every table a one-cell frame); returns that outcome."""
    import types

    import pandas as pd

    from soilcal.loop import cli, core, synthesize

    table = pd.DataFrame({"x": [1.0]})
    summary = pd.DataFrame([{"parameters": "{}", "ci95": "{}", "rmse_before_percent": 17.4,
                             "rmse_after_percent": 17.4, "error_reduction_percent": 0.0}])
    out = types.SimpleNamespace(chosen=[], theta={}, verdict="consistent", summary=summary, residuals=table,
                                diagnosis=table, selection=table, diagnosis_after=None, predictions=table)
    monkeypatch.setattr(cli, "dem_simulator", lambda threads: None)
    monkeypatch.setattr(cli, "condition_params", lambda params: {})
    monkeypatch.setattr(bench, "_campaign", campaign)
    monkeypatch.setattr(synthesize, "synthesize", lambda *a, **k: table)
    monkeypatch.setattr(synthesize, "with_measured", lambda conds, t: conds)
    monkeypatch.setattr(core, "run_inprocess", lambda *a, **k: out)
    return out


def test_a_rerun_campaign_leaves_no_table_of_the_earlier_run(bench, monkeypatch, tmp_path):
    # a campaign rerun where nothing is chosen has no diagnosis after: the earlier run's file of
    # that campaign, which described a choice, must not stay beside the new tables
    _no_dem_loop(bench, monkeypatch, lambda tmp, n, seed, speeds, responses: [])
    detail = tmp_path / "loop_dem"
    detail.mkdir()
    stale = detail / "none_campaign1_diagnosis_after.csv"
    stale.write_text("from an earlier run\n")
    other = detail / "none_diagnosis_after.csv"  # campaign 0's: not this run's
    other.write_text("campaign 0\n")
    rows = bench.dem_rows(["none"], 18, 1, 1, outdir=tmp_path)
    assert rows[0]["case"] == "none" and rows[0]["seed"] == 1
    assert (detail / "none_campaign1_residuals.csv").exists()
    assert not stale.exists()
    assert other.read_text() == "campaign 0\n"


def test_campaign_measures_change_no_condition(bench, tmp_path):
    # the measures a campaign records are response columns only: the same random draws give the
    # same conditions (setups, speeds, depths, covariates), and the default table is the one the
    # campaign always wrote (the horizontal force measured, the vertical force's columns ignored,
    # no angle columns)
    default = bench._campaign(tmp_path / "a", 18, 0)
    both = bench._campaign(tmp_path / "b", 18, 0, responses=("horizontal_force_N", "vertical_force_N"))
    every = bench._campaign(tmp_path / "c", 18, 0, responses=tuple(bench.CAMPAIGN_RESPONSES))
    for other in (both, every):
        assert [(c.setup, c.quantities) for c in other] == [(c.setup, c.quantities) for c in default]
    assert [r["measure"] for r in default[0].responses] == ["horizontal_force_N"]
    assert [r["measure"] for r in both[0].responses] == ["horizontal_force_N", "vertical_force_N"]
    assert [r["unit"] for r in every[0].responses] == ["N", "N", "deg"]
    header = (tmp_path / "a/resources/measurements/cinnamon-soil/campaign.csv").read_text().splitlines()[0]
    assert header == ("directrix,speed_m_s,depth_mm,position_m,day,moisture_pct,horizontal_N,horizontal_sd_N,"
                      "vertical_N,vertical_sd_N,repeats")


def test_campaign_refuses_an_unknown_measure(bench, tmp_path):
    with pytest.raises(ValueError, match="expected one or more of horizontal_force_N"):
        bench._campaign(tmp_path, 18, 0, responses=("draft_N",))


def test_a_campaign_of_other_measures_replaces_nothing(bench):
    both = "horizontal_force_N+vertical_force_N"
    old = _row("rate_friction", 0, "log")  # written before the column existed: the horizontal force
    assert bench._responses_text(old) == "horizontal_force_N"
    assert bench._responses_text(dict(_row("plastic_contact", 0, ""), responses="")) == ""
    assert not bench.replaced(old, [dict(_row("rate_friction", 0, "log"), responses=both)])
    assert bench.replaced(old, [dict(_row("rate_friction", 0, "log"), responses="horizontal_force_N")])
    assert bench.replaced(dict(old, responses=both), [dict(_row("rate_friction", 0, "log"), responses=both)])
    lines = bench._summary([old, dict(_row("rate_friction", 0, "log", "30"), responses=both)])[2:]
    assert lines == ["| dem | rate_friction (measuring horizontal_force_N) | 1 | 1 | 0 |  | 20.00 -> 20.00 |  |  | 1.0 |",
                     "| dem | rate_friction (measuring horizontal_force_N, vertical_force_N) | 1 | 1 | 0 |  | "
                     "30.00 -> 30.00 |  |  | 1.0 |"]
    assert bench.responses_tag(("horizontal_force_N",)) == ""
    assert bench.responses_tag(("horizontal_force_N", "vertical_force_N")) == "_horizontal_vertical"


def test_a_campaign_of_other_measures_keeps_the_default_campaigns_tables(bench, monkeypatch, tmp_path):
    got = {}
    _no_dem_loop(bench, monkeypatch, lambda tmp, n, seed, speeds, responses: got.setdefault("r", responses) and [])
    detail = tmp_path / "loop_dem"
    detail.mkdir()
    default = detail / "none_campaign1_diagnosis_after.csv"  # the horizontal-force campaign's
    default.write_text("horizontal force\n")
    both = ("horizontal_force_N", "vertical_force_N")
    rows = bench.dem_rows(["none"], 18, 1, 1, outdir=tmp_path, responses=both)
    assert got["r"] == both and rows[0]["responses"] == "horizontal_force_N+vertical_force_N"
    assert (detail / "none_campaign1_horizontal_vertical_residuals.csv").exists()
    assert default.read_text() == "horizontal force\n"


def test_header_names_a_merged_campaigns_measures(bench):
    both = dict(_row("rate_friction", 1, "log"), responses="horizontal_force_N+vertical_force_N")
    assert bench._merged_text([("hv/loop.csv", [both]), ("h/loop.csv", [_row("rate_friction", 1, "log")])]) == (
        "; rows taken from other runs: hv/loop.csv: dem rate_friction campaign 1 (log speeds; measuring "
        "horizontal_force_N, vertical_force_N); h/loop.csv: dem rate_friction campaign 1 (log speeds)")


def test_the_stem_names_a_campaigns_spacing_where_it_is_not_the_default(bench):
    # the names the default campaigns' committed tables have: unchanged
    assert bench.detail_stem("rate+depth", 0) == "rate+depth"
    assert bench.detail_stem("rate+depth", 0, "log") == "rate+depth"
    assert bench.detail_stem("rate_friction", 2, "log", ("horizontal_force_N", "vertical_force_N")) == (
        "rate_friction_campaign2_horizontal_vertical")
    # a uniform-speed campaign: its spacing, before its measures
    assert bench.detail_stem("rate+depth", 0, "uniform") == "rate+depth_uniform"
    assert bench.detail_stem("rate_friction", 1, "uniform", ("horizontal_force_N", "vertical_force_N")) == (
        "rate_friction_campaign1_uniform_horizontal_vertical")
    # a compression campaign has neither speeds nor soil-bin measures
    assert bench.detail_stem("plastic_contact", 0, "") == "plastic_contact"
    assert bench.detail_tag(dict(_row("plastic_contact", 1, ""), responses="")) == "plastic_contact_campaign1"
    # a row written before the speeds column existed drew its speeds uniformly
    assert bench.detail_tag(dict(_row("stones", 0, ""), responses="")) == "stones_uniform"
    with pytest.raises(ValueError, match="'Log' is not one of log, uniform"):
        bench.detail_stem("none", 0, "Log")


def test_campaigns_of_the_two_spacings_write_their_own_tables(bench, monkeypatch, tmp_path):
    # one case and campaign run with each spacing: each run's residual table says which campaign
    # it is, and neither overwrites the other's
    import types

    import pandas as pd

    from soilcal.loop import core

    out = _no_dem_loop(bench, monkeypatch, lambda tmp, n, seed, speeds, responses: [speeds])
    monkeypatch.setattr(core, "run_inprocess", lambda name, conds, *a, **k: types.SimpleNamespace(
        **dict(vars(out), residuals=pd.DataFrame({"speeds": conds}))))
    detail = tmp_path / "loop_dem"
    for seed, default in ((0, "rate+depth"), (1, "rate+depth_campaign1")):
        uniform = bench.dem_rows(["rate+depth"], 18, seed, 1, outdir=tmp_path, speeds="uniform")[0]
        log = bench.dem_rows(["rate+depth"], 18, seed, 1, outdir=tmp_path, speeds="log")[0]
        assert (uniform["speeds"], log["speeds"]) == ("uniform", "log")
        assert (detail / f"{default}_residuals.csv").read_text() == "speeds\nlog\n"  # the default name, as before
        assert (detail / f"{default}_uniform_residuals.csv").read_text() == "speeds\nuniform\n"
        # the page's reader finds each row's own tables
        for row in (uniform, log):
            assert (detail / f"{bench.detail_tag(row)}_residuals.csv").read_text() == f"speeds\n{row['speeds']}\n"
            assert (detail / f"{bench.detail_tag(row)}_summary.csv").exists()


def test_the_page_takes_each_spacings_floor_from_its_own_tables(bench, tmp_path):
    # campaign 1 of a case with each spacing, 100 N and 200 N measured (SDs 10 and 20 N over 4
    # repeats) against SDs of 6 and 12 N over 3 seeds: the floor sqrt(0.0037) = 6.08 % in both
    # (test_an_earlier_dem_row_takes_its_floor_from_its_campaign_tables); the log campaign
    # simulates 90 and 210 N (relative residuals 0.1, -0.05: RMS 7.91 %), the uniform one 80
    # and 200 N (0.2, 0: RMS sqrt(0.02) = 14.14 %); nothing chosen, so after = before and
    # the explained share 0 where the error before lies above the floor's 95 % interval (the
    # uniform campaign's), empty where within it (the log campaign's 7.91 %,
    # test_an_earlier_dem_row_takes_its_floor_from_its_campaign_tables)
    import pandas as pd

    detail = tmp_path / "loop_dem"
    detail.mkdir()
    for stem, sim, rel in (("none_campaign1", [90.0, 210.0], [0.1, -0.05]),
                           ("none_campaign1_uniform", [80.0, 200.0], [0.2, 0.0])):
        pd.DataFrame({"measurement": "campaign", "row": [1, 2], "measure": "horizontal_force_N",
                      "simulation": ["a", "b"], "measured": [100.0, 200.0], "measured_sd": [10.0, 20.0],
                      "measured_n": [4.0, 4.0], "simulated_mean": sim, "simulated_sd": [6.0, 12.0],
                      "simulated_n": [3, 3], "scale": [100.0, 200.0], "relative_residual": rel}
                     ).to_csv(detail / f"{stem}_residuals.csv", index=False)
    log, uniform = _row("none", 1, "log", "7.91"), _row("none", 1, "uniform", "14.14")
    from soilcal.loop import residuals as rs

    hi = rs.floor_interval(rs.usable(pd.read_csv(detail / "none_campaign1_residuals.csv")))[1]
    assert 0.0791 < hi < 0.1414
    assert bench.floor_of(log, detail) == (6.08, "")
    assert bench.floor_of(uniform, detail) == (6.08, 0.0)
    # a row written before the speeds column existed is a uniform-speed campaign's
    assert bench.floor_of(dict(uniform, speeds=""), detail) == (6.08, 0.0)


def test_per_measure_finds_each_spacings_table(load_benchmark, tmp_path):
    pm = load_benchmark("loop_rate/per_measure.py", "per_measure_bench")
    log = tmp_path / "rate_friction_campaign1_horizontal_vertical_residuals.csv"
    uniform = tmp_path / "rate_friction_campaign1_uniform_horizontal_vertical_residuals.csv"
    for p in (log, uniform):
        p.write_text("x\n1\n")
    assert pm.residual_table("rate_friction:1", tmp_path) == log
    assert pm.residual_table("rate_friction:1:log", tmp_path) == log
    assert pm.residual_table("rate_friction:1:uniform", tmp_path) == uniform
    assert pm.residual_table(str(uniform), tmp_path) == uniform  # a table's path, as given
    with pytest.raises(ValueError, match="no residual table .*rate_friction_campaign2_horizontal_vertical"):
        pm.residual_table("rate_friction:2", tmp_path)
    with pytest.raises(ValueError, match="'rate_friction:1:Log': speed spacing 'Log' is not one of"):
        pm.residual_table("rate_friction:1:Log", tmp_path)
