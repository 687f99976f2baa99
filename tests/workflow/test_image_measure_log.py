"""The image_measure job's log names every drum frame a group set aside and every frame flagged
low that the user accepted (accept_low), as ``soilcal image`` warns of them on stderr."""

from __future__ import annotations

import types
from pathlib import Path

import yaml

from soilcal.imaging import render

SCRIPT = Path(__file__).resolve().parents[2] / "workflow" / "scripts" / "image_measure.py"


def test_the_log_names_frames_set_aside_and_accepted_low(tmp_path):
    # before: a frame flagged low and averaged by accept_low: true left no line in the log (the
    # JSON held it in accepted_low), so a group's angle silently included a frame the measurement
    # doubted; a frame set aside was logged as a "photo"
    img, truth = render.render_tester_frame(3, 40.0, fill=0.35, size=(240, 240), window="crop", n_avg=4)
    (cx, cy), R = truth["centre_px"], truth["radius_px"]
    for name in ("b.png", "c.png"):
        render.save_frame(tmp_path / name, img)
    # a drum given 1.3 times too large and 0.25 radii off its centre: the surface ends short of it
    wrong = {"drum_centre_px": [cx + 0.25 * R, cy + 0.1 * R], "drum_radius_px": 1.3 * R}
    entry = {"kind": "drum", "group": "dyn", "level": "image"}
    (tmp_path / "m.yaml").write_text(yaml.safe_dump({"photos": [
        entry | {"file": "b.png", **wrong},
        entry | {"file": "c.png", "accept_low": True, **wrong}]}))
    job = types.SimpleNamespace(log=[str(tmp_path / "logs/image_measure.log")],
                                output=types.SimpleNamespace(json=str(tmp_path / "out/m.json"),
                                                             figures=str(tmp_path / "out/figs")),
                                params=types.SimpleNamespace(refusals=str(tmp_path / "logs/refused"),
                                                             manifest=str(tmp_path / "m.yaml"), threshold="otsu"))
    exec(compile(SCRIPT.read_text(), str(SCRIPT), "exec"), {"snakemake": job, "__name__": "__main__"})
    log = (tmp_path / "logs/image_measure.log").read_text()
    lines = log.splitlines()
    aside = [x for x in lines if "b.png" in x]
    accepted = [x for x in lines if "c.png" in x]
    assert len(accepted) == 1 and "group dyn: frame" in accepted[0] and "accepted by the user" in accepted[0], log
    assert "averaged into the group's angle" in accepted[0], log
    assert "short of the drum circle" in accepted[0]
    assert len(aside) == 1 and "group dyn: frame" in aside[0] and "set aside" in aside[0], log
    # as soilcal image words it: the angle it is left out of, the frames behind the angle
    assert "not averaged into the group's angle; 1 frame used" in aside[0], log
    assert "short of the drum circle" in aside[0]
