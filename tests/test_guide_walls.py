"""The guide P drawn and reported as what it is (issue 45, item 5): its wear map's four bands
are its four walls (+y, -y, +z, -z; docs/physics.md 5.7, ``core.prismatic.WALLS``), each
``npolar // 4`` rows across the wall by ``nazim`` columns along the guide.

Before, ``--kind wear-map`` drew two panels, each with two walls stacked and offset on one
axis labelled "+y" and "-y" (no position across the wall), and its title said "Socket and
guide wear depth" of a run with no socket clearance; ``report`` had P's depth only as the
whole map's largest bin, and per-axis projection columns that are zero for P.
"""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.core.prismatic import WALLS
from clearsweep.plotting import figure
from clearsweep.plotting.common import guide_extent, scaled

#: A clearance at the guide P alone (0.2 mm across y, 0.1 mm across z): one revolution at
#: 600 r/min on a 16 x 24 map (4 rows a wall).
GUIDE_ALONE = ["joints.P.clearance_y=2e-4", "joints.P.clearance_z=1e-4", "mechanism.speed_rpm=600",
               "solver.duration=0.1", "metrics.settle_time=0.02", "wear.map=[16,24]"]


@pytest.fixture(scope="module")
def guide_alone(tmp_path_factory):
    path = tmp_path_factory.mktemp("guide") / "guide.nc"
    result = CliRunner().invoke(main, ["run", "configs/ideal.yaml",
                                       *[a for s in GUIDE_ALONE for a in ("--set", s)],
                                       "-q", "-o", str(path)])
    assert result.exit_code == 0, result.output
    return path


def _bands(ds: xr.Dataset) -> list[np.ndarray]:
    """P's wear map [m] cut in its four walls' bands, in ``WALLS`` order."""
    wmap = ds["wear_map"].sel(joint="P").values
    band = wmap.shape[0] // len(WALLS)
    return [wmap[w * band:(w + 1) * band] for w in range(len(WALLS))]


def test_the_wear_map_draws_each_guide_wall_as_a_strip_of_its_band(guide_alone):
    ds = xr.load_dataset(guide_alone)
    bands = _bands(ds)
    assert any(b.max() > 0 for b in bands)      # the corners wore the walls
    fig = figure(ds, "wear-map")
    strips = [ax for ax in fig.axes if ax.collections and ax.get_label() != "<colorbar>"]
    assert len(strips) == len(WALLS)
    factor, unit = scaled(ds["wear_map"])
    x0, span, half_y_wall, half_z_wall = guide_extent(ds)
    for ax, wall, band in zip(strips, WALLS, bands):
        (mesh,) = ax.collections
        assert ax.get_title().startswith(f"guide P: {wall} wall")
        # the colour data are the wall's band, bin for bin, in the scale's unit
        np.testing.assert_allclose(np.asarray(mesh.get_array()).reshape(band.shape), band / factor,
                                   rtol=1e-12)
        # axes in mm: along the guide over the map's span, across the wall over its extent
        corners = mesh.get_coordinates()
        half = half_y_wall if wall in ("+y", "-y") else half_z_wall
        np.testing.assert_allclose([corners[..., 0].min(), corners[..., 0].max()],
                                   [1e3 * x0, 1e3 * (x0 + span)])
        np.testing.assert_allclose([corners[..., 1].min(), corners[..., 1].max()],
                                   [-1e3 * half, 1e3 * half])
        assert ax.get_ylabel().endswith("[mm]")
        # one colour scale for the four walls: the largest depth of any
        assert mesh.norm.vmax == pytest.approx(max(b.max() for b in bands) / factor)
    assert strips[-1].get_xlabel() == "position along the guide x [mm]"
    assert fig.get_suptitle().startswith("Guide wear depth")


def test_the_report_gives_the_track_depth_of_each_guide_wall_in_its_own_column(guide_alone):
    with xr.open_dataset(guide_alone) as ds:
        expected = {wall: float(band.max()) for wall, band in zip(WALLS, _bands(ds))}
    runner = CliRunner()
    rows = list(csv.DictReader(io.StringIO(
        runner.invoke(main, ["report", str(guide_alone), "--format", "csv"]).stdout)))
    assert {r["joint"] for r in rows} == {"P"}
    for wall, depth in expected.items():
        assert {float(r[f"Track depth, {wall} wall [m]"]) for r in rows} == {depth}
    records = json.loads(runner.invoke(main, ["report", str(guide_alone), "--format", "json"]).stdout)
    sign = {"+": "plus", "-": "minus"}
    for record in records["rows"]:
        assert {w: record[f"track_depth_max_{sign[w[0]]}_{w[1]}"] for w in WALLS} == expected
    text = runner.invoke(main, ["report", str(guide_alone)]).stdout
    table = text.split("Guide walls at the end of the run", 1)[1].split("\n\n")[1].splitlines()
    assert [h.strip() for h in table[1].split("  ") if h.strip()] == [f"{w} wall [nm]" for w in WALLS]
    (row,) = [line for line in table if line.startswith("P ")]
    printed = [float(v) for v in row.split()[1:]]
    np.testing.assert_allclose(printed, [1e9 * expected[w] for w in WALLS], rtol=5e-4)


def test_a_life_figure_of_the_guide_draws_its_snapshots_as_wall_strips():
    """A life run with a clearance at the guide alone: its snapshot panels drew P's map
    against "polar" and "azimuth" angles, a socket's axes; they now draw its four walls'
    bands, labelled, along the guide in mm."""
    from test_figure_layout import CONFIG, TINY_LIFE, layout_problems

    from clearsweep.config import load_config
    from clearsweep.service_life import life

    ds = life(load_config(CONFIG, [*TINY_LIFE, "joints.B.clearance=0", "joints.P.clearance_y=1e-4",
                                   "joints.P.clearance_z=1e-4", "life.max_blocks=2"]))
    fig = figure(ds, "life")
    assert "wear maps of guide P" in fig.get_suptitle()
    panels = [ax for ax in fig.axes if ax.collections and ax.get_title().startswith("guide P")]
    assert panels
    factor, _ = scaled(ds["wear_map_snapshot"])
    for ax, k in zip(panels, range(ds.sizes["snapshot"])):
        (mesh,) = ax.collections
        snapshot = ds["wear_map_snapshot"].sel(joint="P").isel(snapshot=k).values
        np.testing.assert_allclose(np.asarray(mesh.get_array()).reshape(snapshot.shape),
                                   snapshot / factor, rtol=1e-12)
        assert [t.get_text() for t in ax.get_yticklabels()] == [f"{w} wall" for w in WALLS]
        assert ax.get_xlabel() == "along the guide x [mm]"
    assert layout_problems(fig) == []
