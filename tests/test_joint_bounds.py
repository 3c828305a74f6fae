"""Every joint size and wear coefficient drawn over many decades: `validate` and `run` either
accept it or refuse it in one error line, never with a traceback, and never leave a file."""
from __future__ import annotations

from pathlib import Path

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
    assert {p.crank_length_m for p in PRESETS.values()} == {config_module.CRANK_LENGTH_M}
    assert max(max(p.crank_length_m, p.rod_length_m) for p in PRESETS.values()) \
        == config_module.LONGEST_LINK_M


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
    """Below its Hertz sink (static penetration under the start's joint reaction) a clearance
    stops the run at once on penetration_exceeded: validate says so, naming the joint."""
    result = CliRunner().invoke(main, ["validate", "-q", ONE, "--set", f"joints.{joint}.clearance=1e-9"])
    assert result.exit_code == 0, result.output
    warnings = [line for line in result.stderr.splitlines() if line.startswith("clearsweep: warning:")]
    assert len(warnings) == 1 and f"joint {joint}'s Hertz sink" in warnings[0], result.stderr
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
def test_the_hertz_sink_warning_foretells_the_penetration_stop(joint, clearance_m, tmp_path):
    """validate warns of a clearance exactly when a run of it stops on penetration_exceeded in
    its first 2 ms: the warning is the kernel's stop told before any run (the guide P
    included, its load shared by the four corners of the loaded face)."""
    sets = [a for key in SINK_KEYS[joint] for a in ("--set", f"{key}={clearance_m}")]
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
