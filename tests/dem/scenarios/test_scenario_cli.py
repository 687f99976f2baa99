"""``soilcal scenario`` commands: list, one run writing one CSV row, errors naming the field."""

import csv

from soilcal.cli import main


def test_list_names_the_scenarios(capsys):
    assert main(["scenario", "list"]) == 0
    out = capsys.readouterr().out
    for name in ("repose", "drum", "incline", "compression"):
        assert name in out


def test_run_writes_one_row(tmp_path, capsys):
    out = tmp_path / "row.csv"
    rc = main(["scenario", "run", "incline", "--setup", "yangtze-rolling", "--threads", "1",
               "--set", "start_deg=4", "--param", "soil_steel_rolling_friction=0.097",
               "--seed", "5", "--out", str(out)])
    assert rc == 0
    rows = list(csv.DictReader(open(out)))
    assert len(rows) == 1
    row = rows[0]
    assert row["scenario"] == "incline" and row["seed"] == "5" and row["preset"] == "quick"
    assert float(row["p:soil_steel_rolling_friction"]) == 0.097
    assert float(row["s:start_deg"]) == 4.0
    assert 5.3 < float(row["r:onset_deg"]) < 5.9   # atan(0.097) = 5.54 deg
    assert float(row["wall_s"]) > 0 and int(row["n_particles"]) == 1


def test_replicates_average_the_runs(tmp_path, capsys):
    out = tmp_path / "row.csv"
    rc = main(["scenario", "run", "incline", "--setup", "yangtze-rolling", "--threads", "1",
               "--set", "start_deg=4", "--param", "soil_steel_rolling_friction=0.097",
               "--seed", "5", "--replicates", "2", "--out", str(out)])
    assert rc == 0
    row = list(csv.DictReader(open(out)))[0]
    assert row["seed"] == "5" and row["s:replicates"] == "2" and row["s:replicate_seeds"] == "5 6"
    assert 5.3 < float(row["r:onset_deg"]) < 5.9   # atan(0.097) = 5.54 deg
    # one sphere on a plane: nothing random, so the seeds give the same onset
    assert float(row["r:onset_deg_rep_sd"]) == 0.0
    assert '"per_run"' in capsys.readouterr().out
    assert main(["scenario", "run", "incline", "--replicates", "0"]) == 2
    assert "--replicates: expected an integer >= 1" in capsys.readouterr().err


def test_replicates_of_a_heap(tmp_path):
    # each seed draws other radii, so the runs' time steps differ: still one averaged row
    out = tmp_path / "row.csv"
    assert main(["scenario", "run", "repose", "--threads", "1", "--set", "n_particles=400",
                 "--replicates", "2", "--out", str(out)]) == 0
    row = list(csv.DictReader(open(out)))[0]
    assert row["s:replicate_seeds"] == "0 1" and 0.0 < float(row["r:angle_deg"]) < 90.0
    assert float(row["r:angle_deg_rep_sd"]) > 0.0  # two seeds, two heaps


def test_bad_values_exit_2_naming_the_field(capsys):
    assert main(["scenario", "run", "repose", "--set", "tube_diameter=0.5"]) == 2
    err = capsys.readouterr().err
    assert "setup.tube_diameter" in err and "narrower than the plate" in err
    assert main(["scenario", "run", "repose", "--param", "soil_soil_restitution=2"]) == 2
    assert "params.soil_soil_restitution" in capsys.readouterr().err
    assert main(["scenario", "run", "drum", "--set", "no_such_key=1"]) == 2
    assert main(["scenario", "run", "drum", "--preset", "slow"]) == 2


def test_vtk_frames_are_written_and_readable(tmp_path):
    from soilcal.dem.io import read_pvd, read_vtk_arrays

    rc = main(["scenario", "run", "incline", "--setup", "yangtze-rolling", "--threads", "1",
               "--set", "start_deg=5", "--vtk", str(tmp_path / "vtk")])
    assert rc == 0
    frames = read_pvd(tmp_path / "vtk" / "incline.pvd")
    assert len(frames) == 2  # settled on the plate, and at the rolling onset
    assert frames[1][0] > frames[0][0]
    arrays = read_vtk_arrays(frames[1][1])
    assert arrays["PointData/radius"].shape == (1,) and arrays["PointData/radius"][0] == 0.010
