"""GrainLearning's iterative Bayesian calibration of one case, its DEM runs done by soilcal.

Runs in GrainLearning's own environment (``grainlearning`` pins numpy < 2, soilcal needs
numpy >= 2), so it imports neither soilcal nor pandas: ``benchmarks/adaptive_gl.py`` writes
the problem as JSON, starts this script with that environment's Python, and evaluates every
batch of parameter samples GrainLearning asks for through its own command (the same DEM jobs
as the workflow's, in soilcal's environment).

    <gl-python> benchmarks/adaptive_gl_driver.py problem.json

problem.json: ``names``, ``low``, ``high`` (the free factors and their ranges), ``responses``
and ``targets`` (one observation per response), ``samples`` (per iteration), ``iterations``,
``seed`` (the Gaussian mixture's random state and the first DEM seed), ``ess_target``,
``evaluate`` (the command that runs a batch: it is called with the batch file and the output
file appended), ``workdir``.  Iteration k writes ``batch_<k>.json`` (parameter samples and
their seeds) and reads ``sims_<k>.json`` (one value per sample and response); at the end
``result.json`` holds every iteration's samples and responses, the last iteration's posterior and the most probable
sample of the last iteration (GrainLearning's estimate, ``get_most_prob_params``); ``collapsed``
says when a posterior on a single sample ended the calibration early (empty otherwise).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from grainlearning import BayesianCalibration


def _compute_errors(self):
    """``BayesianCalibration.compute_errors`` for static targets: GrainLearning divides each
    sample's absolute error by the observations' range, which is 0 for a single static target
    (the division gives inf and scikit-learn refuses it); that case takes |target| instead.
    Only the printed errors use this (and the ``error_tol`` stop, which is not set here)."""
    obs = np.asarray(self.system.obs_data, float)
    scale = float(obs.max() - obs.min()) or float(np.abs(obs).max()) or 1.0
    sim = np.asarray(self.system.sim_data, float)
    self.error_array = np.abs(sim - obs[None]).mean(axis=(1, 2)) / scale
    self.gl_errors.append(float(np.dot(self.error_array, self.inference.posterior)))


BayesianCalibration.compute_errors = _compute_errors


def main(path: str) -> None:
    prob = json.loads(Path(path).read_text())
    wd = Path(prob["workdir"])
    history = []
    next_seed = [int(prob["seed"])]

    def callback(calib):
        it = int(calib.curr_iter)
        params = np.asarray(calib.system.param_data, float)
        seeds = list(range(next_seed[0], next_seed[0] + len(params)))
        next_seed[0] += len(params)
        batch, out = wd / f"batch_{it}.json", wd / f"sims_{it}.json"
        batch.write_text(json.dumps({"iteration": it, "names": prob["names"], "params": params.tolist(),
                                     "seeds": seeds}))
        subprocess.run([*prob["evaluate"], str(batch), str(out)], check=True)
        values = np.asarray(json.loads(out.read_text())["values"], float)  # (samples, responses)
        history.append({"iteration": it, "params": params.tolist(), "seeds": seeds, "values": values.tolist()})
        # a failed run has no value; GrainLearning's likelihood cannot take NaN, so such a
        # sample gets the batch's value farthest from the target (it is counted, and named in
        # the result)
        for j, t in enumerate(prob["targets"]):
            col = values[:, j]
            bad = ~np.isfinite(col)
            if bad.any():
                ok = col[~bad]
                col[bad] = ok[np.argmax(np.abs(ok - t))] if ok.size else 10.0 * abs(t) + 1.0
        calib.system.set_sim_data(values[:, :, None])

    calib = BayesianCalibration.from_dict({
        "num_iter": int(prob["iterations"]),
        "callback": callback,
        "system": {
            "param_names": prob["names"],
            "param_min": prob["low"],
            "param_max": prob["high"],
            "num_samples": int(prob["samples"]),
            "obs_names": prob["responses"],
            "obs_data": [[float(t)] for t in prob["targets"]],
            "ctrl_data": [0.0],
            "sim_name": "soilcal",
        },
        "inference": {
            "Bayes_filter": {"ess_target": float(prob["ess_target"])},
            "sampling": {"max_num_components": 2, "random_state": int(prob["seed"]), "slice_sampling": False},
        },
        "save_fig": -1,
    })
    collapsed = ""
    try:
        calib.run()
    except ValueError:
        # GrainLearning resamples from its posterior by fitting a Gaussian mixture to the
        # samples drawn with the posterior's weights, normalised by their range; when the
        # posterior holds (nearly) all its weight on one sample, every drawn sample is that
        # one, the range is 0 and the normalisation gives NaN (scikit-learn then refuses the
        # fit).  The iteration's inference is complete by then: its most probable sample is
        # the estimate, as after a last iteration; any other error is re-raised.
        s = calib.inference.sampling
        hi, lo = getattr(s, "max_params", None), getattr(s, "min_params", None)
        if not history or hi is None or not np.any(np.asarray(hi) == np.asarray(lo)):
            raise
        collapsed = (f"posterior of iteration {len(history) - 1} on one sample "
                     f"(GrainLearning cannot resample from it): estimate taken there")
        print(f"GrainLearning stopped: {collapsed}", flush=True)
    last = np.asarray(calib.inference.posterior).ravel()
    best = int(np.argmax(last))
    (wd / "result.json").write_text(json.dumps({
        "iterations_run": len(history),
        "most_probable": dict(zip(prob["names"], map(float, calib.system.param_data[best]))),
        "most_probable_index": best,
        "last_posterior": last.tolist(),
        "sigma_max": float(calib.system.sigma_max),
        "collapsed": collapsed,
        "history": history,
    }))


if __name__ == "__main__":
    main(sys.argv[1])
