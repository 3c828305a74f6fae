"""Results describe every joint (issue 42 item 4): each joint's type, materials and the
contact values the kernel ran with (the packed ``jp`` rows), O and P included, in a single
run's attributes and, where they vary from case to case, in a sweep's variables."""

import math

import numpy as np
import xarray as xr
import yaml

from clearsweep.config import load_config
from clearsweep.core import layout as L
from clearsweep.core.joints import JOINTS
from clearsweep.params import BASE_MATERIAL, JOINT_ATTRIBUTES, joint_attributes
from clearsweep.simulation import preflight, simulate
from clearsweep.sweeping import run_sweep

#: Clearance at all four joints, B coated: a short run (a few hundred steps).
FOUR = {"joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4, "coating": "PTFE"},
                   "O": {"clearance": 1.0e-4},
                   "P": {"clearance_y": 1.0e-4, "clearance_z": 2.0e-4}},
        "solver": {"duration": 0.003}}


def _packed(doc):
    return preflight(load_config(doc), seat=False)


def test_every_joint_has_its_attributes_and_they_are_the_packed_values():
    ds = simulate(FOUR)
    jp = _packed(FOUR).jp
    for j, joint in enumerate(JOINTS):
        attrs = {key: ds.attrs[f"joint_{joint.name}_{key}"] for key in JOINT_ATTRIBUTES}
        assert attrs["type"] == joint.type
        assert attrs["contact"] != "ideal"
        assert attrs["modulus_Pa"] == jp[j, L.J_EW]
        assert attrs["friction_coefficient"] == jp[j, L.J_MU]
        assert attrs["wear_coefficient_m2_per_N"] == jp[j, L.J_K]
        assert attrs["clearance_m"] == jp[j, L.J_C]
        assert attrs["base_material"] == BASE_MATERIAL
    assert ds.attrs["joint_P_clearance_m"] == 1.0e-4        # P's smaller clearance
    assert ds.attrs["joint_B_coating"] == ds.attrs["joint_B_surface_material"] == "PTFE"
    assert ds.attrs["joint_O_surface_material"] == BASE_MATERIAL
    # O's journal takes Hertz's law, P's faces an elastic foundation with Hertz's E*
    # (docs/physics.md 3.7); A and B the paper's layered law
    assert ds.attrs["joint_O_contact"].startswith("Hertz")
    assert ds.attrs["joint_P_contact"].startswith("elastic foundation")
    assert ds.attrs["joint_A_contact"].startswith("layered")
    # the kernel's values differ between the joints: not one value copied four times
    assert ds.attrs["joint_O_modulus_Pa"] != ds.attrs["joint_A_modulus_Pa"]
    assert ds.attrs["joint_B_friction_coefficient"] != ds.attrs["joint_A_friction_coefficient"]


def test_an_ideal_joint_says_ideal():
    ds = simulate({"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.002}})
    for name in ("A", "O", "P"):
        assert ds.attrs[f"joint_{name}_contact"] == "ideal"
        assert math.isnan(ds.attrs[f"joint_{name}_modulus_Pa"])
        assert ds.attrs[f"joint_{name}_clearance_m"] == 0.0
    assert ds.attrs["joint_O_type"] == "revolute" and ds.attrs["joint_P_type"] == "prismatic"
    assert ds.attrs["joint_B_contact"] != "ideal"


def test_a_sweep_keeps_shared_joint_values_global_and_varying_ones_per_case(tmp_path):
    base = {"joints": {"B": {"clearance": 2.5e-4}}, "solver": {"duration": 0.002}}
    sweep = {"grid": {"joints.B.coating": ["none", "PTFE"], "joints.A.clearance": [0.0, 2.5e-4]}}
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump({"name": "s", "base": base, "sweep": sweep}, sort_keys=False))
    run_sweep(path, tmp_path / "s.nc", workers=1, progress=False).close()
    with xr.open_dataset(tmp_path / "s.nc") as ds:
        # the same in every case: global attributes
        assert ds.attrs["joint_O_type"] == "revolute" and ds.attrs["joint_O_contact"] == "ideal"
        assert "joint_B_modulus_Pa" not in ds.attrs
        # varying: a variable over the sweep dims, each case's packed value
        var = ds["joint_B_modulus_Pa"]
        assert set(var.dims) == {"B_coating", "A_clearance"} and var.attrs["units"] == "Pa"
        for coating in ("none", "PTFE"):
            for clearance in (0.0, 2.5e-4):
                doc = {**base, "joints": {"A": {"clearance": clearance},
                                          "B": {"clearance": 2.5e-4, "coating": coating}}}
                jp = _packed(doc).jp
                case = ds.sel(B_coating=coating, A_clearance=clearance)
                def value(name, case=case):
                    return case[name].item() if name in ds else ds.attrs[name]

                assert value("joint_B_modulus_Pa") == jp[1, L.J_EW]
                assert value("joint_B_friction_coefficient") == jp[1, L.J_MU]
                assert value("joint_B_wear_coefficient_m2_per_N") == jp[1, L.J_K]
                assert (value("joint_A_contact") == "ideal") == (clearance == 0.0)
        assert np.unique(var.values).size == 2


def test_a_life_run_describes_its_joints_as_a_run_does():
    """A life run's dataset carries the same per-joint attributes as a run of its block
    (service_life built its own dataset without them); a reliability or life sweep then
    keeps them as a run sweep does."""
    from clearsweep.service_life import block_config, life

    doc = {**FOUR, "mechanism": {"speed_rpm": 1200.0}, "life": {"cycles": 1.0, "block_revolutions": 1},
           "wear": {"map": [12, 24]}}
    cfg = load_config(doc)
    ds = life(cfg)
    block = block_config(cfg)
    expected = joint_attributes(block, preflight(block, seat=False))
    assert len(expected) == len(JOINTS) * len(JOINT_ATTRIBUTES)
    for name, value in expected.items():
        got = ds.attrs[name]
        assert got == value or (isinstance(value, float) and math.isnan(value) and math.isnan(got)), name
    assert ds.attrs["joint_B_coating"] == "PTFE" and ds.attrs["joint_P_type"] == "prismatic"
    assert ds.attrs["joint_O_contact"].startswith("Hertz")
