"""
Bifurcation diagram over crank speed
====================================

Is the motion periodic, period-n or chaotic, and where does it change? A sweep over one
parameter with the Poincaré samples of every case (one point per crank revolution) answers
it: :func:`clearsweep.plotting.figure` with ``kind="bifurcation"`` draws each case's last
10 samples against the swept value (docs/physics.md section 11).

``configs/bifurcation.yaml`` sweeps joint B's mechanism (0.25 mm clearance) over 60 crank
speeds from 50 to 640 r/min, 110 revolutions each. Here the same sweep runs 7 speeds around
the change that single runs show between 90 and 100 r/min (below, the ball comes back to
the same point of its socket every revolution; above, it does not), 14 revolutions each
with 4 of start-up, in this process (``workers=1``): real runs of the kernel (about 6
million RK4 steps, some 20 s), not a synthetic dataset.
"""

from pathlib import Path

import yaml

import clearsweep
from clearsweep.analysis import format_sweep_summary
from clearsweep.plotting import figure

# the shipped configs, found from anywhere inside the repository (the docs build runs
# this script from docs/examples)
CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents)
               if (p / "configs" / "life.yaml").is_file())

spec = yaml.safe_load((CONFIGS / "bifurcation.yaml").read_text())
spec["sweep"]["grid"]["mechanism.speed_rpm"] = [70.0, 80.0, 90.0, 100.0, 110.0, 130.0, 160.0]
spec["base"]["solver"]["revolutions"] = 14              # at each speed its own seconds
spec["base"]["metrics"]["settle_revolutions"] = 4       # of start-up
ds = clearsweep.sweep(spec, workers=1, progress=False)

# %%
# The report names the periodic and the non-periodic speeds (``clearsweep report FILE``):
print(format_sweep_summary(ds).split("Motion")[-1])

# %%
# The diagram (``clearsweep plot FILE --kind bifurcation --x speed_rpm -o bif.png``):
# a single dot per speed where the motion repeats every revolution, a smear where it does
# not.
bifurcation = figure(ds, "bifurcation", x="speed_rpm")
