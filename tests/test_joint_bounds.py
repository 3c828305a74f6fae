"""Every joint size and wear coefficient drawn over many decades: `validate` and `run` either
accept it or refuse it in one error line, never with a traceback, and never leave a file."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner
from hypothesis import example, given, settings
from hypothesis import strategies as st

import clearsweep.config as config_module
from clearsweep.cli import main
from clearsweep.params import PRESETS

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
ONE = str(CONFIGS / "one_clearance.yaml")

#: Each key of O and P, and A/B's where the same hole exists.
KEYS = ["joints.O.clearance", "joints.O.bearing_radius", "joints.O.length",
        "joints.O.coating_thickness", "joints.O.base_thickness", "joints.O.wear_coefficient",
        "joints.P.clearance_y", "joints.P.clearance_z", "joints.P.corner_radius",
        "joints.P.coating_thickness", "joints.P.base_thickness", "joints.P.wear_coefficient",
        "joints.A.clearance", "joints.B.clearance", "joints.A.coating_thickness",
        "joints.B.base_thickness", "joints.A.wear_coefficient", "joints.B.wear_coefficient"]

#: Many decades, both signs, zero, denormals and the largest floats.
VALUES = st.one_of(
    st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 2.2e-308, 1e-300, 1e300, 1.7976931348623157e308]),
    st.builds(lambda sign, exponent, mantissa: sign * mantissa * 10.0 ** exponent,
              st.sampled_from([1.0, -1.0]), st.integers(-320, 300), st.floats(1.0, 9.99)))


def test_the_bounds_follow_the_mechanism():
    assert set(config_module.PRESET_LINKS_M) == set(PRESETS)
    for name, preset in PRESETS.items():
        assert config_module.PRESET_LINKS_M[name] == (
            preset.crank_length_m, max(preset.crank_length_m, preset.rod_length_m))
    rssp = [p for p in PRESETS.values() if p.kind == "rssp"]
    assert {p.crank_length_m for p in rssp} == {config_module.CRANK_LENGTH_M}
    assert max(max(p.crank_length_m, p.rod_length_m) for p in rssp) == config_module.LONGEST_LINK_M


@pytest.mark.parametrize("key", KEYS)
@settings(max_examples=25, deadline=None)
@given(value=VALUES, other=st.sampled_from(KEYS), second=VALUES)
@example(value=5e-324, other="joints.P.corner_radius", second=1e-300)
def test_validate_of_any_size_is_ok_or_one_error_line(key, value, other, second):
    result = CliRunner().invoke(main, ["validate", ONE, "--set", f"{key}={value!r}",
                                       "--set", f"{other}={second!r}"])
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        f"{type(result.exception).__name__}: {result.exception}"
    assert "Traceback" not in result.output + result.stderr
    assert result.exit_code in (0, 2), result.output
    errors = [line for line in result.stderr.splitlines() if "error" in line]
    assert len(errors) == (result.exit_code == 2)
    if errors:
        assert errors[0].startswith("clearsweep: error: ")


@pytest.mark.parametrize("setting", ["joints.O.clearance=5e-324", "joints.O.bearing_radius=1000",
                                     "joints.P.corner_radius=1e-300", "joints.O.wear_coefficient=1e300"])
def test_run_of_a_refused_size_writes_no_file(tmp_path, setting):
    out = tmp_path / "out.nc"
    result = CliRunner().invoke(main, ["run", ONE, "--set", setting, "-o", str(out)])
    assert result.exit_code == 2 and not list(tmp_path.iterdir()), result.output


@pytest.mark.parametrize("joint", ["O", "B"])
def test_validate_warns_of_a_clearance_below_the_hertz_sink(joint):
    """Below its Hertz sink (static penetration under the start's joint reaction) a joint sits
    deeper than its clearance, beyond the small contact its law describes: validate says so
    before any run, naming the joint, and that the run goes on (docs/physics.md 4.3)."""
    result = CliRunner().invoke(main, ["validate", "-q", ONE, "--set", f"joints.{joint}.clearance=1e-9"])
    assert result.exit_code == 0, result.output
    warnings = [line for line in result.stderr.splitlines() if line.startswith("clearsweep: warning:")]
    assert len(warnings) == 1 and f"joint {joint}'s Hertz sink" in warnings[0], result.stderr
    assert "the run goes on" in warnings[0]
    well_above = CliRunner().invoke(main, ["validate", "-q", ONE, "--set", f"joints.{joint}.clearance=1e-6"])
    assert well_above.exit_code == 0 and "warning" not in well_above.stderr, well_above.stderr


def test_the_hertz_sink_warning_follows_the_clearance():
    """The Python helper gives the warning for 1 nm at B and none for the shipped 0.25 mm."""
    from clearsweep.config import load_config, resolve_materials
    from clearsweep.params import hertz_sink_warnings

    cfg = load_config(ONE, ["joints.B.clearance=1e-9"])
    assert hertz_sink_warnings(cfg, resolve_materials(cfg))
    cfg = load_config(ONE, ["joints.B.clearance=2.5e-4"])
    assert not hertz_sink_warnings(cfg, resolve_materials(cfg))


#: The clearance keys of each joint that the sink warning covers (P: both of its gaps).
SINK_KEYS = {"O": ["joints.O.clearance"], "B": ["joints.B.clearance"],
             "P": ["joints.P.clearance_y", "joints.P.clearance_z"]}


@pytest.mark.parametrize("joint", sorted(SINK_KEYS))
@pytest.mark.parametrize("clearance_m", [1e-9, 1e-7, 1e-6])
def test_the_hertz_sink_warning_foretells_the_fractional_stop(joint, clearance_m, tmp_path):
    """With the stop at a fraction of the clearance (contact.max_penetration_fraction 0.5, the
    rule before issue 41 item 4), validate warns of a clearance exactly when a run of it
    stops on penetration_exceeded in its first 2 ms: the warning is the kernel's stop told
    before any run (the guide P included, its load shared by the four corners of the loaded
    face)."""
    sets = [a for key in SINK_KEYS[joint] for a in ("--set", f"{key}={clearance_m}")]
    sets += ["--set", "contact.max_penetration_fraction=0.5"]
    if joint != "B":
        sets += ["--set", "joints.B.clearance=0"]
    base = [str(CONFIGS / "ideal.yaml"), *sets, "--set", "wear.map=[6,12]"]
    checked = CliRunner().invoke(main, ["validate", "-q", *base])
    assert checked.exit_code == 0, checked.output
    # P's faces sink under the load (docs/physics.md 3.7), the balls and the journal by Hertz
    warned = ("contact sink" if joint == "P" else "Hertz sink") in checked.stderr
    out = tmp_path / "run.nc"
    CliRunner().invoke(main, ["run", "-q", *base, "--set", "solver.duration=0.002", "-o", str(out)])
    with xr.open_dataset(out) as ds:
        stopped = str(ds["status"].values) == "penetration_exceeded"
    assert warned == stopped, (warned, str(checked.stderr))


@pytest.mark.parametrize("joint", sorted(SINK_KEYS))
@pytest.mark.parametrize("clearance_m", [1e-9, 1e-8, 3e-8])
def test_a_tiny_clearance_runs_under_the_physical_stop(joint, clearance_m, tmp_path):
    """A clearance below about 3e-8 m at the mechanism's loads used to stop at the first step
    (the stop at half the clearance lay inside the Hertz sink). The stop is now the depth at
    which the joint's law carries contact.load_bound (docs/physics.md 4.3), so the run goes
    on; validate still warns where the sink passes the clearance, and says the run goes on.
    Measured sinks: O 6.3, 13.7, 19.7 nm; B 1.65, 3.3, 5.2 nm; P 1.3 um (28.8 N)."""
    sets = [a for key in SINK_KEYS[joint] for a in ("--set", f"{key}={clearance_m}")]
    if joint != "B":
        sets += ["--set", "joints.B.clearance=0"]
    base = [str(CONFIGS / "ideal.yaml"), *sets, "--set", "wear.map=[6,12]"]
    checked = CliRunner().invoke(main, ["validate", "-q", *base])
    assert checked.exit_code == 0, checked.output
    warnings = [line for line in checked.stderr.splitlines() if "Hertz sink" in line]
    assert all("the run goes on" in line and f"joint {joint}'s" in line for line in warnings)
    out = tmp_path / "run.nc"
    result = CliRunner().invoke(main, ["run", "-q", *base, "--set", "solver.duration=0.002",
                                       "-o", str(out)])
    assert result.exit_code == 0, result.output
    with xr.open_dataset(out) as ds:
        assert str(ds["status"].values) == "ok"
        assert float(ds["penetration_peak"].sel(joint=joint)) > 0.0


@pytest.mark.parametrize("thickness_m, load_bound_N", [(1e-4, 100.0)])
def test_an_excessive_penetration_still_stops(thickness_m, load_bound_N):
    """The centred start's impact at B (0.25 mm, PTFE-lined: 4.6 um deep) passes the physical
    stop where the stop is small: a load bound of 100 N. The run stops on
    penetration_exceeded at the impact (t = 5.3 ms), keeping its rows before it. Before
    (half the clearance, 125 um) it ran."""
    from clearsweep.simulation import simulate

    ds = simulate({"joints": {"A": {"clearance": 0.0},
                              "B": {"clearance": 2.5e-4, "coating": "PTFE",
                                    "coating_thickness": thickness_m}},
                   "contact": {"load_bound": load_bound_N},
                   "initial": {"joints": "centred"}, "solver": {"duration": 0.02}})
    assert str(ds["status"].values) == "penetration_exceeded"
    kept = ds["time"].values[np.isfinite(ds["slider_position"].values)]
    assert 0.004 < kept[-1] < 0.007


def test_the_penetration_stop_is_the_laws_depth_at_the_load_bound():
    """params.penetration_stop: the depth at which the joint's own law carries
    contact.load_bound (uncoated B: the paper's law; O: the journal's; P: one edge line's
    law, touching at its end corner only, and no deeper than a tenth of the edges' radius),
    whatever a coating's thickness; contact.max_penetration_fraction given, that fraction
    of the clearance, as before."""
    from clearsweep.config import load_config, resolve_materials
    from clearsweep.core import layout as L
    from clearsweep.core.contact import elastic_force
    from clearsweep.core.joints import INDEX
    from clearsweep.core.prismatic import line_load, line_stiffness
    from clearsweep.params import pack

    cfg = load_config(ONE, ["joints.O.clearance=1e-4", "joints.P.clearance_y=1e-4",
                            "joints.P.clearance_z=1e-4", "contact.load_bound=5e4"])
    packed = pack(cfg, resolve_materials(cfg), seat=False)
    for name in ("B", "O"):
        row = packed.jp[INDEX[name]]
        law = 0.0 if name == "B" else 1.5
        force = elastic_force(row[L.J_PEN_STOP], row[L.J_C], row[L.J_EW], row[L.J_RI],
                              row[L.J_RJ], law)[0]
        assert force == pytest.approx(5e4, rel=1e-9)
    # P: one edge line touching at its end corner only carries the bound at the stop (the
    # softer wall's lines), and the stop is inside a tenth of the 1 mm edges' radius
    row = packed.jp[INDEX["P"]]
    one = np.ascontiguousarray(row[None, :])
    kl = min(line_stiffness(one, 0, wall, row[L.J_EW]) for wall in (0, 2))
    fa, fb, _ = line_load(row[L.J_PEN_STOP], 0.0, kl, row[L.J_BLOCK_LENGTH])
    assert fa + fb == pytest.approx(5e4, rel=1e-12)
    assert row[L.J_PEN_STOP] < 0.1 * row[L.J_CORNER_RADIUS]
    heavy = load_config(ONE, ["joints.P.clearance_y=1e-4", "joints.P.clearance_z=1e-4",
                              "contact.load_bound=1e7"])
    row = pack(heavy, resolve_materials(heavy), seat=False).jp[INDEX["P"]]
    assert row[L.J_PEN_STOP] == pytest.approx(0.1 * row[L.J_CORNER_RADIUS], rel=1e-15)
    # a coating's thickness does not cap the stop: the penetration is the bodies' approach,
    # which the base carries under a thin layer; both stops lie beyond the thin layer's 1 um
    thin, thick = (load_config(ONE, ["joints.B.coating=PTFE", f"joints.B.coating_thickness={t}"])
                   for t in (1e-6, 1e-4))
    stops = [pack(c, resolve_materials(c), seat=False).jp[INDEX["B"], L.J_PEN_STOP]
             for c in (thin, thick)]
    assert stops[0] > 1e-6 and stops[1] > 1e-6
    old = load_config(ONE, ["contact.max_penetration_fraction=0.5"])
    row = pack(old, resolve_materials(old), seat=False).jp[INDEX["B"]]
    assert row[L.J_PEN_STOP] == 0.5 * row[L.J_C]
