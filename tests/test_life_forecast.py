"""A life or reliability plan gives an expected time beside its upper bound (issue 34 item 3).

Before, ``life --dry-run`` and the plan of a life or reliability sweep printed only the
upper bound, ``life.max_blocks`` blocks for every run: the reliability example's "at most
about 21.3 min" ran in 1 min 55 s. The expected blocks come from the depth walk of
:func:`clearsweep.service_life.forecast_blocks`: a jump grows the bin that limits it by
what ``life.jump_*_fraction`` allows, whatever the wear rate, so the block at which a wear
limit is crossed follows from the config (benchmarks/README.md, "Life and reliability
plans": the estimate against the wall time of the shipped examples).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.config import load_config
from clearsweep.service_life import forecast_blocks, life

ROOT = Path(__file__).resolve().parent.parent
CASE = str(ROOT / "configs/one_clearance.yaml")
#: A life run that wear ends within a few blocks: 300 r/min (0.2 s blocks), a coarse map,
#: wear x300, to 70 um of wear at B (tests/test_figure_layout.py's TINY_LIFE).
TINY_LIFE = ["mechanism.speed_rpm=300", "metrics.settle_time=0.02", "wear.map=[8,16]",
             "wear.interpolate=true", "solver.energy_tolerance=0.5", "wear.amplification=300",
             "life.cycles=1e5", "life.jump_clearance_fraction=0.1",
             "life.max_clearance_growth=7e-5"]

_UNITS = {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0}


def _seconds(text: str, before: str) -> float:
    """The duration that follows ``before`` in ``text`` ("at most about 1.33 min") [s]."""
    match = re.search(re.escape(before) + r" ([0-9.e+]+) (s|min|h|d)\b", text)
    assert match, f"no {before!r} in: {text}"
    return float(match.group(1)) * _UNITS[match.group(2)]


@pytest.mark.parametrize("argv", [
    ["life", "configs/life.yaml", "--dry-run"],
    ["sweep", "configs/reliability.yaml", "--dry-run", "--workers", "2"],
    ["sweep", "configs/life_sweep.yaml", "--dry-run", "--workers", "2"],
], ids=lambda a: a[1])
def test_the_plan_gives_an_expected_time_beside_the_bound(argv, monkeypatch):
    monkeypatch.chdir(ROOT)
    result = CliRunner().invoke(main, argv)
    assert result.exit_code == 0, result.output
    bound = _seconds(result.output, "at most about")
    expected = _seconds(result.output, "expected about")
    assert 0.0 < expected <= bound
    assert "blocks" in result.output.split("expected about", 1)[1]


def test_the_reliability_example_is_expected_in_a_fraction_of_its_bound(monkeypatch):
    """Its members reach their wear limit (40 um at jumps of 2 % of 0.25 mm) in 9 blocks of
    the 200 the bound counts: about 1.1 min expected on 2 workers, 21.5 min at most."""
    monkeypatch.chdir(ROOT)
    result = CliRunner().invoke(main, ["sweep", "configs/reliability.yaml", "--dry-run",
                                       "--workers", "2"])
    assert "9 blocks a run to its wear limits (life.max_clearance_growth)" in result.output
    assert _seconds(result.output, "expected about") < 0.1 * _seconds(result.output, "at most about")


def test_the_joint_with_the_smallest_allowance_sets_the_pace():
    """configs/reliability_joints.yaml: 40 um of wear at jumps of 2 % of each joint's
    clearance. A's and B's 0.25 mm allow 5 um a jump (9 blocks); O's and P's 0.1 mm 2 um,
    and either can cut every jump: 21 blocks (its members ran about 24, issue 45)."""
    from clearsweep.schema import read_yaml

    cfg = load_config(read_yaml(ROOT / "configs" / "reliability_joints.yaml")["base"])
    assert forecast_blocks(cfg, every_limit=True).blocks == 21
    only_b = load_config(read_yaml(ROOT / "configs" / "reliability_joints.yaml")["base"],
                         ["joints.O.clearance=0", "joints.A.clearance=0",
                          "joints.P.clearance_y=0", "joints.P.clearance_z=0"])
    assert forecast_blocks(only_b, every_limit=True).blocks == 9


@pytest.mark.parametrize("extra, limit", [
    ([], "clearance_growth"),
    (["joints.B.coating=MoS2", "joints.B.coating_thickness=5e-5",
      "life.stop_at_wear_through=true", "life.max_clearance_growth=null"], "wear_through"),
])
def test_the_forecast_is_the_blocks_a_run_that_wear_ends_takes(extra, limit):
    """Two runs that a wear limit ends: at 2.5e-5 m a jump, 7e-5 m of clearance growth is
    crossed in the fourth block; a 50 um MoS2 coating, with jumps of a quarter of what is
    left of it (and at least a quarter of a quarter of it), wears through in the tenth."""
    cfg = load_config(CASE, TINY_LIFE + extra)
    forecast = forecast_blocks(cfg)
    ds = life(cfg)
    assert str(ds["stop_reason"].values) == limit
    assert forecast.limits == (limit,)
    assert forecast.blocks == ds.sizes["cycle"] == (4 if limit == "clearance_growth" else 10)


def test_the_forecast_never_passes_the_bound():
    life_yaml = str(ROOT / "configs/life.yaml")
    cfg = load_config(life_yaml)
    assert forecast_blocks(cfg).blocks == 101        # 0.25 mm at 1 % of 0.25 mm a jump
    assert forecast_blocks(load_config(life_yaml, ["life.max_blocks=50"])).blocks == 50
    # at most the blocks that reach life.cycles without a jump
    assert forecast_blocks(load_config(life_yaml, ["life.cycles=20"])).blocks == 20
    # nothing to forecast from: the bound, said so
    for overrides in (["life.max_clearance_growth=null", "life.max_normal_force=30"],
                      ["wear.enabled=false"]):
        forecast = forecast_blocks(load_config(life_yaml, overrides))
        assert (forecast.blocks, forecast.limits) == (200, ())
        assert "no wear limit watched" in forecast.describe(cfg)
    # a reliability member waits for every limit: the later of the two
    both = load_config(life_yaml, ["joints.B.coating_thickness=5e-5",
                                   "life.stop_at_wear_through=true"])
    first, every = forecast_blocks(both), forecast_blocks(both, every_limit=True)
    assert first.limits == every.limits == ("clearance_growth", "wear_through")
    assert first.blocks < every.blocks <= 200


def test_a_life_names_the_joint_that_reaches_a_limit_first():
    """Each joint against the limit: the first_joint_to_* of a life run is the joint whose
    own series crosses it first (here B, the one with clearance, of A, B, O, P), the report
    names it, and a reliability sweep counts it per design."""
    import numpy as np
    import xarray as xr

    from clearsweep.reliability import _first_joints
    from clearsweep.service_life import crossing_cycle, life_summary_text

    cfg = load_config(CASE, TINY_LIFE)
    ds = life(cfg)
    assert str(ds["stop_reason"].values) == "clearance_growth"
    depth = ds["wear_depth_max"].values
    crossings = [crossing_cycle(ds["cycle"].values, depth[:, j], 7e-5) for j in range(depth.shape[1])]
    first = str(ds["joint"].values[int(np.nanargmin(crossings))])
    assert first == "B" == str(ds["first_joint_to_clearance_growth"].values)
    assert str(ds["first_joint_to_motion_error"].values) == ""     # not set
    assert "revolutions to life.max_clearance_growth: " in life_summary_text(ds)
    assert "(joint B first)" in life_summary_text(ds)
    flat = xr.Dataset({"first_joint": (("design", "member", "limit"),
                                       np.array([[["B", "B"], ["P", "P"], ["B", "B"], ["", ""]]],
                                                dtype=object))},
                      coords={"limit": ["clearance_growth", "any"]})
    rows = [("B_coating=none", flat.isel(design=0).sel(limit="any"))]
    assert _first_joints(flat, "any", rows) == [
        "which joint reaches any first:",
        "  B_coating=none: first to reach it: joint B in 2 members, joint P in 1 member"]
