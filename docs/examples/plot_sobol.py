"""
Sobol' indices
==============

Which input sets the slider's vibration? ``configs/sensitivity.yaml`` draws a Saltelli
sample over B's clearance, its PTFE coating's thickness, the restitution and the crank
speed; :func:`clearsweep.sensitivity.sweep_indices` gives the first-order and total
Sobol' indices (S1, ST) with 95 % bootstrap intervals (SALib). The shipped file uses
n = 512 base points; here n = 16 and 0.1 s per case, so the intervals are wide.
"""

from pathlib import Path

import yaml

import clearsweep
from clearsweep.sensitivity import format_indices, indices_figure, sweep_indices

# the shipped configs, found from anywhere inside the repository (the docs build runs
# this script from docs/examples)
CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents)
               if (p / "configs" / "life.yaml").is_file())

spec = yaml.safe_load((CONFIGS / "sensitivity.yaml").read_text())
spec["sweep"]["sample"]["n"] = 16
spec["base"]["solver"]["duration"] = 0.1
spec["base"]["metrics"] = {"settle_time": 0.02}
ds = clearsweep.sweep(spec, workers=1, progress=False)
print(ds.sizes)

# %%
# Indices of the settled RMS slider acceleration
# (``clearsweep sensitivity FILE --metric slider_acceleration_rms_settled -o sobol.png``):
result = sweep_indices(ds, "slider_acceleration_rms_settled")
print(format_indices(result))
sobol = indices_figure(result)
