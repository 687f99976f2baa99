"""Is p = 0.0556 (depth_compaction campaign 1) a floor of the paired test?  The one-sided paired
t-test (scipy ttest_rel, the loop's test) has none: with k folds all gaining nearly alike its
p goes to 0.  A sign-flip or signed-rank test over k folds has one: 2^-k (k = 4: 0.0625).
And the campaign's folds: at bce2311 the loop held out test days only where the first
diagnosis found the days different (raw p < 0.05); campaign 1's day test had p 0.626
(loop_dem/depth_compaction_campaign1_uniform_diagnosis.csv, a uniform-speed campaign, as it was
then; the table there now is the campaign's rerun at 5389f15), so the folds were its 18
conditions.
    python benchmarks/loop_depth/p_floor.py
"""
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/loop.py
import loop as B
for k in (4, 18):
    gain = 1.0 + 0.01 * np.linspace(-1, 1, k)
    print(f"k {k}: t-test p with every fold gaining 1 +- 0.01: {stats.ttest_rel(gain, np.zeros(k), alternative='greater').pvalue:.3g}; "
          f"signed-rank exact floor: {stats.wilcoxon(gain, alternative='greater', method='exact').pvalue:.4g} (2^-k = {2.0 ** -k:.4g})")
d = pd.read_csv(B.HERE / "results/loop_dem" / f"{B.detail_stem('depth_compaction', 1, 'uniform')}_diagnosis.csv")
print(d[(d["test"] == "group") & (d["covariate"] == "day")][["covariate", "p", "p_adjusted"]].to_string(index=False))
print(f"1/18 = {1 / 18:.5f}; the printed p 0.05564 (selection.csv)")
