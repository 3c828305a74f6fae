"""Service life by cycle jumps (docs/service_life.md): jump rule, wear-through switching,
volume conservation, convergence with the jump limit, agreement with a direct run."""

import math

import numpy as np
import pytest

from clearsweep.config import ConfigError, load_config, resolve_materials
from clearsweep.core import layout as L
from clearsweep.params import pack
from clearsweep.service_life import bin_areas, crossing_cycle, jump_revolutions, life
from clearsweep.simulation import run_kernel, simulate
from clearsweep.variables import format_length

CASE = "configs/one_clearance.yaml"
#: a coarse map read bilinearly, as configs/life.yaml reads its own; the default energy
#: tolerance (the force follows the worn surface, docs/physics.md 3.5). Coarser maps than
#: 36 x 72 (5 degree bins) make V-shaped valleys under a worn-in ball (docs/service_life.md)
SMALL = ["wear.map=[36,72]", "wear.interpolate=true"]


def test_jump_limited_by_clearance_and_remaining_coating():
    depth = np.zeros((2, 2, 2))
    rate = np.zeros((2, 2, 2))
    rate[1, 0, 0] = 1e-9
    clearance = np.array([0.0, 2.5e-4])
    uncoated = np.array([math.inf, math.inf])
    assert jump_revolutions(depth, rate, clearance, uncoated, 0.1, 0.25) == pytest.approx(2.5e4)
    coated = np.array([math.inf, 1e-5])
    assert jump_revolutions(depth, rate, clearance, coated, 0.1, 0.25) == pytest.approx(2.5e3)
    depth[1, 0, 0] = 1e-5 - 1e-8          # almost through: the floor f^2 l_c applies
    assert jump_revolutions(depth, rate, clearance, coated, 0.1, 0.25) == pytest.approx(625.0)
    assert jump_revolutions(depth, 0 * rate, clearance, coated, 0.1, 0.25) == math.inf


def test_crossing_cycle_interpolates():
    assert crossing_cycle(np.array([1.0, 11.0]), np.array([0.0, 10.0]), 5.0) == pytest.approx(6.0)
    assert math.isnan(crossing_cycle(np.array([1.0, 11.0]), np.array([0.0, 1.0]), 5.0))


def test_bad_life_value_names_the_key():
    with pytest.raises(ConfigError, match="life.jump_coating_fraction"):
        load_config(CASE, ["life.jump_coating_fraction=0"])
    with pytest.raises(ConfigError, match="life.max_normal_force"):
        load_config(CASE, ["life.max_normal_force=-1"])


def _kernel(overrides, wmap):
    cfg = load_config(CASE, [*SMALL, "solver.duration=0.1", *overrides])
    packed = pack(cfg, resolve_materials(cfg), wmap)
    return packed, run_kernel(packed, wmap, np.zeros(L.N_JOINTS))


def test_worn_through_coating_contacts_as_the_base_material():
    """A PTFE socket worn through everywhere (feedback off, so the geometry is the unworn
    one) behaves exactly as the uncoated steel socket."""
    worn = np.full((L.N_JOINTS, 36, 72), 2e-4)
    packed, coated = _kernel(["joints.B.coating=PTFE", "wear.feedback=false"], worn)
    assert packed.jp[1, L.J_EW_BASE] > packed.jp[1, L.J_EW]
    _, steel = _kernel(["wear.feedback=false"], worn)
    _, fresh = _kernel(["joints.B.coating=PTFE", "wear.feedback=false"], 0 * worn)
    assert coated.status == steel.status == "ok"
    assert np.array_equal(coated.stats, steel.stats)
    assert np.array_equal(coated.wvol, steel.wvol)
    assert not np.allclose(fresh.stats, steel.stats)
    assert np.all(coated.d[-1, L.D_WORN + 1] == 1.0)
    assert fresh.d[-1, L.D_WORN + 1] == 0.0


#: A short life run: MoS2 at B, a 1 um coating that wears through, 30 revolutions.
SHORT_LIFE = [*SMALL, "wear.amplification=1000", "life.cycles=30",
              "life.jump_clearance_fraction=0.05", "joints.B.coating=MoS2",
              "joints.B.coating_thickness=1e-6"]


@pytest.fixture(scope="module")
def short_life(short_life_cli):
    """The SHORT_LIFE run, as ``clearsweep life`` wrote it (tests/conftest.py: once per
    session); the life sweep below checks it bit for bit against the Python call."""
    import xarray as xr

    return xr.load_dataset(short_life_cli[0])


@pytest.mark.slow
def test_volume_conserved_across_blocks_and_jumps(short_life):
    ds = short_life
    assert ds.sizes["cycle"] >= 3 and float(ds.jump_revolutions.sum()) > 0
    areas = bin_areas(ds.wear_map.shape[1:], 0.015)
    on_map = float((ds.wear_map.sel(joint="B").values * areas).sum())
    volume = float(ds.wear_volume.isel(cycle=-1).sel(joint="B"))
    assert on_map == pytest.approx(volume, rel=1e-9)
    for k in range(ds.sizes["snapshot"]):
        snap = float((ds.wear_map_snapshot.isel(snapshot=k).sel(joint="B").values * areas).sum())
        row = ds.wear_volume.sel(cycle=float(ds.snapshot_cycle[k])).sel(joint="B")
        assert snap == pytest.approx(float(row), rel=1e-9)
    # the 1 um coating is worn through on the way, and the dataset says where and when
    assert 0 < float(ds.wear_through_cycle.sel(joint="B")) < 30
    assert np.isfinite(ds.wear_through_polar.sel(joint="B"))
    assert ds.wear_depth_max.attrs["units"] == "m"
    assert ds.cycle.attrs["units"] == "1"


@pytest.mark.slow
def test_cycles_to_limit_converge_as_the_jump_limit_is_halved():
    """First order in the jump limit: 1093, 1219, 1274, 1310 revolutions at 0.04, 0.02,
    0.01, 0.005 (docs/service_life_verification.py, quoted in docs/service_life.md); below
    5 % change from 0.01 to 0.005."""
    common = [*SMALL, "wear.amplification=300", "life.cycles=1e4", "life.max_clearance_growth=4e-5"]
    cycles = [float(life(CASE, [*common, f"life.jump_clearance_fraction={f}"]).cycles_to_clearance_growth)
              for f in (0.01, 0.005)]
    assert all(np.isfinite(cycles))
    assert abs(cycles[1] - cycles[0]) / cycles[1] < 0.05


@pytest.mark.slow
def test_life_agrees_with_a_direct_simulation():
    """12 revolutions with wear amplified 2000 times: jumps against every revolution
    simulated (docs/service_life.md states the measured agreement)."""
    common = ["wear.map=[36,72]", "wear.interpolate=true", "wear.amplification=2000",
              "joints.B.coating=MoS2"]
    direct = simulate(CASE, [*common, "solver.duration=12", "solver.save_every=1000"])
    jumped = life(CASE, [*common, "life.cycles=12", "life.jump_clearance_fraction=0.01"])
    assert float(jumped.jump_revolutions.sum()) > 4
    v_direct = float(direct.wear_volume.sel(joint="B"))
    v_life = float(jumped.wear_volume.isel(cycle=-1).sel(joint="B"))
    assert v_life == pytest.approx(v_direct, rel=1e-3)      # measured -3.9e-4
    h_direct = float(direct.wear_map.sel(joint="B").max())
    h_life = float(jumped.wear_depth_max.isel(cycle=-1).sel(joint="B"))
    assert h_life == pytest.approx(h_direct, rel=0.2)       # measured +12.7 %


@pytest.mark.slow
def test_life_cli_writes_a_dataset_that_plots_and_reports(tmp_path, short_life_cli, short_life):
    from click.testing import CliRunner

    from clearsweep.cli import main
    from clearsweep.plotting import plot

    out, run = short_life_cli
    # one progress line per block on stderr, the summary on stdout, the file named last
    blocks = [ln for ln in run.stderr.splitlines() if ln.startswith("  block at ")]
    assert len(blocks) == short_life.sizes["cycle"]
    assert run.stderr.splitlines()[-1] == f"clearsweep: wrote {out}"
    fig = plot(short_life, "life", tmp_path / "life.png", dpi=40)
    assert len(fig.axes) >= 2 and (tmp_path / "life.png").stat().st_size > 0
    report = CliRunner().invoke(main, ["report", str(out)])
    assert report.exit_code == 0, report.output
    # the report is what `life` printed, and states the run's own numbers
    assert report.stdout == run.stdout
    lines = report.stdout.splitlines()
    assert lines[0] == (f"life run: {short_life.sizes['cycle']} blocks, "
                        f"{float(short_life.cycle[-1]):.4g} revolutions, "
                        f"stopped by {short_life.stop_reason.values}")
    through = float(short_life.wear_through_cycle.sel(joint="B"))
    assert f"  coating of B worn through at {through:.4g} revolutions" in report.stdout
    depth = float(short_life.wear_depth_max.isel(cycle=-1).sel(joint="B"))
    assert f"  B at the end: max depth {format_length(depth)}, " in report.stdout


@pytest.mark.slow
def test_a_life_sweep_stores_each_design_s_life_summary(tmp_path, short_life, process_pool):
    """store: life runs every case as a life run and keeps revolutions to each limit and the
    final wear per design; the MoS2 design is the short life run above, bit for bit."""
    from clearsweep.config import load_config
    from clearsweep.sweeping import run_sweep

    base = load_config(CASE, SHORT_LIFE).to_dict()
    doc = {"name": "life_sweep", "store": "life", "base": base,
           "sweep": {"grid": {"joints.B.coating": ["MoS2", "PTFE"]}}}
    with run_sweep(doc, tmp_path / "life_sweep.nc", client=process_pool, progress=False) as ds:
        assert list(ds.status.values) == ["ok", "ok"]
        assert "time" not in ds.dims and "cycle" not in ds.dims
        mos2 = ds.sel(B_coating="MoS2")
        assert float(mos2.cycles_reached) == float(short_life.cycle[-1])
        np.testing.assert_array_equal(mos2.wear_volume_final.values,
                                      short_life.wear_volume.isel(cycle=-1).values)
        np.testing.assert_array_equal(mos2.wear_through_cycle.values,
                                      short_life.wear_through_cycle.values)
        assert ds.wear_depth_max_final.attrs["units"] == "m"
        assert str(mos2.stop_reason.values) == str(short_life.stop_reason.values)
        # a coating of the same thickness with other values wears through at another time
        assert float(ds.cycles_to_wear_through.sel(B_coating="PTFE")) != float(
            mos2.cycles_to_wear_through)
    from click.testing import CliRunner

    from clearsweep.cli import main

    report = CliRunner().invoke(main, ["report", str(tmp_path / "life_sweep.nc")])
    assert report.exit_code == 0, report.output
    assert "Service life per design" in report.output
    assert "B_coating=MoS2" in report.output and "B_coating=PTFE" in report.output


def test_the_guide_s_mean_depth_is_the_plain_mean_of_its_track_bins():
    """A life run's wear_depth_mean of P is the plain mean of its bins deeper than 1 % of the
    largest (each bin a piece of the corners' track, docs/physics.md 5.7), not a mean
    weighted by the bins' areas on the walls: here a y wall's bins are 1.4 times a z wall's
    (block 50 mm wide, 70 mm high) and both kinds are worn, so the two means differ."""
    cfg = load_config("configs/one_clearance.yaml",
                      ["joints.B.clearance=0", "joints.P.clearance_y=1e-4",
                       "joints.P.clearance_z=1e-4", "joints.P.block=[0.08, 0.05, 0.07]",
                       "wear.map=[36, 72]", "wear.interpolate=true", "solver.dt=2e-5",
                       "life.cycles=2"])     # two blocks, no jump: the map is the last row's
    ds = life(cfg)
    wmap = ds.wear_map.sel(joint="P").values
    worn = wmap > 1e-2 * wmap.max()
    band = wmap.shape[0] // 4
    walls = np.repeat(np.arange(4), band)[:, None] * np.ones(wmap.shape[1], dtype=int)
    assert worn[walls < 2].any() and worn[walls >= 2].any()     # y and z walls
    mean = float(ds.wear_depth_mean.isel(cycle=-1).sel(joint="P"))
    assert mean == pytest.approx(wmap[worn].mean(), rel=1e-12)
    weights = np.where(walls < 2, 0.0702, 0.0502)[worn]        # the walls' heights
    assert abs((wmap[worn] * weights).sum() / weights.sum() / mean - 1.0) > 1e-3
