"""Issue 19: ftcal GP vs the stock sklearn GP and the LTM on the simulated soft sensor, 5-fold (eq. 18 RMSE, 2-std coverage).

Usage: nice -n 19 python benchmarks/gp_vs_stock_soft.py stock
"""
import time, sys, numpy as np, warnings
warnings.simplefilter("ignore")
from ftcal import make_soft_sensor_dataset
from ftcal.models import stock_baselines
from ftcal import GaussianProcessCalibrator, LinearCalibrator
import ftcal
from sklearn.model_selection import KFold
from threadpoolctl import threadpool_limits
d = make_soft_sensor_dataset()
a = d.meta["alpha"]; print("floor", d.meta["noise_floor_rmse"], "alpha", a)
def rmse(p): return ftcal.wrench_rmse(d.wrench, p, a)
models = [("ltm", lambda: LinearCalibrator(alpha=a)), ("gp", lambda: GaussianProcessCalibrator(alpha=a, random_state=0))]
if "stock" in sys.argv: models.append(("sk_gp", lambda: stock_baselines(8)["sk_gp"]))
for name, make in models:
    pred = np.zeros_like(d.wrench); cover=[]; t=time.perf_counter()
    for tr, te in KFold(5, shuffle=True, random_state=0).split(d.raw):
        with threadpool_limits(1):
            m = make().fit(d.raw[tr], d.wrench[tr])
        if name == "gp":
            pred[te], sd = m.predict(d.raw[te], return_std=True); cover.append(np.abs(pred[te]-d.wrench[te]) <= 2*sd)
            print(m.mean_, m.kernel_, m.per_output_, {k: round(v,1) for k,v in m.log_marginal_likelihood_.items()}, flush=True)
        else: pred[te] = m.predict(d.raw[te])
    print(name, rmse(pred), time.perf_counter()-t, np.mean(np.vstack(cover)) if cover else "", flush=True)
