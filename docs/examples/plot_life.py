"""
A life curve
============

:func:`clearsweep.life` alternates short dynamic blocks on the worn geometry with jumps
that add many revolutions' worth of each block's wear (docs: *Service life*). Here the
shipped ``configs/life.yaml`` (MoS2 in socket B, 0.25 mm clearance) up to 10^5
revolutions on a coarser wear map, so that it runs in seconds.
"""

from pathlib import Path

import clearsweep
from clearsweep.plotting import figure
from clearsweep.service_life import life_summary_text

# the shipped configs, found from anywhere inside the repository (the docs build runs
# this script from docs/examples)
CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents)
               if (p / "configs" / "life.yaml").is_file())

ds = clearsweep.life(CONFIGS / "life.yaml", overrides=["life.cycles=1e5", "wear.map=[36, 72]"])
print(life_summary_text(ds))

# %%
# Wear, clearance, coating left, force and vibration against revolutions, and the wear
# map's evolution (``clearsweep plot life.nc --kind life``):
curve = figure(ds, "life")
