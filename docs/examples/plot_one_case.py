"""
One case and its plots
======================

Two spherical joints with 0.25 mm of radial clearance (``configs/two_clearances.yaml``),
PTFE in the slider-side socket B, a quarter of a crank turn. :func:`clearsweep.simulate`
returns a labelled :class:`xarray.Dataset`; :func:`clearsweep.plotting.figure` draws the
same figures as ``clearsweep plot``.
"""

from pathlib import Path

import clearsweep
from clearsweep.analysis import run_summary_text
from clearsweep.plotting import figure

# the shipped configs, found from anywhere inside the repository (the docs build runs
# this script from docs/examples)
CONFIGS = next(p / "configs" for p in (Path.cwd(), *Path.cwd().parents)
               if (p / "configs" / "life.yaml").is_file())

ds = clearsweep.simulate(CONFIGS / "two_clearances.yaml",
                         overrides=["joints.B.coating=PTFE", "solver.duration=0.25"])
print(run_summary_text(ds))

# %%
# Every variable carries its units and long name:
print(ds["normal_force"].attrs)

# %%
# Slider position, velocity and acceleration against the crank angle
# (``clearsweep plot out.nc --kind slider``):
slider = figure(ds, "slider")

# %%
# The force on each ball, magnitude and components (``--kind forces``):
forces = figure(ds, "forces")

# %%
# Each ball's path inside its clearance circle (``--kind orbit``):
orbit = figure(ds, "orbit")
