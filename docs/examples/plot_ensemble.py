"""
Ensemble comparison with error bars
===================================

A clearance joint is sensitive to its start and to material scatter, so a comparison of
coatings means something only with an error bar. ``configs/coating_ensemble.yaml`` runs
every design as perturbed members (ball start, crank phase, wear coefficient); here with
8 members and one clearance. The file gains a ``member`` dimension and, per design, the
mean with its 95 % Student t interval.
"""

from pathlib import Path

import yaml

import clearsweep
from clearsweep.analysis import format_ensemble_report
from clearsweep.plotting import figure

# the shipped configs, found from anywhere inside the repository (the docs build runs
# this script from docs/examples)
CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents)
               if (p / "configs" / "life.yaml").is_file())

spec = yaml.safe_load((CONFIGS / "coating_ensemble.yaml").read_text())
spec["base"]["ensemble"]["members"] = 8
spec["base"]["solver"]["duration"] = 0.15
spec["sweep"]["grid"]["joints.B.clearance"] = [2.5e-4]
ds = clearsweep.sweep(spec, workers=1, progress=False)
print(format_ensemble_report(ds))

# %%
# The ensemble mean of the settled RMS slider acceleration per coating, with its 95 %
# interval as error bars (``clearsweep plot FILE --kind sweep``):
bars = figure(ds, "sweep", metric="slider_acceleration_rms_settled",
              select={"B_clearance": 2.5e-4})
