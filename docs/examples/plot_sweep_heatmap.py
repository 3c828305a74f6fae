"""
Coating x clearance sweep: a heat map
=====================================

The main job (``configs/coating_clearance.yaml``) swept over the coating in socket B and
B's clearance, here with clearance at B only, 0.1 s per case and summaries only, so that
it runs in seconds in this process (``workers=1``). A sweep is a mapping or a YAML file;
:func:`clearsweep.sweep` returns one labelled dataset with a dimension per sweep axis.
"""

from pathlib import Path

import yaml

import clearsweep
from clearsweep.plotting import figure

# the shipped configs, found from anywhere inside the repository (the docs build runs
# this script from docs/examples)
CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents)
               if (p / "configs" / "life.yaml").is_file())

spec = yaml.safe_load((CONFIGS / "coating_clearance.yaml").read_text())
spec["store"] = "summary"                       # no time series, no wear map per case
spec["base"]["solver"] = {"duration": 0.1}     # 0.25 of a revolution, not the job's 6
spec["base"].pop("metrics")                     # nor its settled revolution
spec["base"]["wear"]["map"] = [72, 144]
del spec["sweep"]["zip"]                        # joint A stays ideal
ds = clearsweep.sweep(spec, workers=1, progress=False)
print(ds["slider_acceleration_peak"].sizes)

# %%
# The peak slider acceleration over both axes (``clearsweep plot FILE --kind sweep``):
heat = figure(ds, "sweep", metric="slider_acceleration_peak")

# %%
# And the peak crank torque that drives it:
torque = figure(ds, "sweep", metric="crank_torque_peak")
