"""The kernel built per joint set (core/jointset.py): which set a case has, which build runs
it, that its own build gives the generic build's results bit for bit, that a build without
one of the case's joints is refused, and that the on-disk cache keeps a build per set."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from clearsweep.config import DEFAULTS, resolve_materials
from clearsweep.core import jointset
from clearsweep.core.joints import INDEX
from clearsweep.params import build_of, joint_set, kernel_build, pack
from clearsweep.simulation import run_kernel

ROOT = Path(__file__).resolve().parents[1]

#: overrides -> the joints with clearance they give
SETS = [
    ((), ()),
    (("joints.B.clearance=2.5e-4",), ("B",)),
    (("joints.A.clearance=2.5e-4", "joints.B.clearance=2.5e-4"), ("A", "B")),
    (("joints.O.clearance=5e-5",), ("O",)),
    (("joints.P.clearance_y=2e-4", "joints.P.clearance_z=2e-4"), ("P",)),
    (("joints.A.clearance=2.5e-4", "joints.O.clearance=5e-5", "joints.P.clearance_y=2e-4",
      "joints.P.clearance_z=2e-4"), ("A", "O", "P")),
]


def _packed(overrides, duration=0.004):
    cfg = DEFAULTS.replace(*overrides, f"solver.duration={duration}")
    return cfg, pack(cfg, resolve_materials(cfg))


@pytest.mark.parametrize("overrides, names", SETS)
def test_the_joint_set_is_the_joints_the_config_gives_clearance(overrides, names):
    """params.joint_set (from the config) and jointset.of (from the packed flags the kernel
    tests) name the same joints, those with clearance; the build that runs the case holds
    them."""
    cfg, packed = _packed(overrides)
    expected = sum(1 << INDEX[name] for name in names)
    assert joint_set(cfg) == jointset.of(packed.jp) == expected
    assert jointset.names(expected) == names
    assert jointset.named(*names) == expected
    assert kernel_build(cfg) == build_of(expected)
    # the CPU's builds are specialised on A and B, the device's on every joint
    assert build_of(expected) == expected | jointset.named("O", "P")
    assert build_of(expected, device=True) == expected


def test_a_build_without_a_joint_of_the_case_is_refused():
    """A case with clearance at P on the kernel built for A and B would run P as an ideal
    guide: refused, naming both sets; a build with more joints than the case runs it."""
    _, packed = _packed(SETS[4][0], duration=1e-4)
    with pytest.raises(ValueError, match="clearance at P cannot run on the kernel built for A,B"):
        run_kernel(packed, build=jointset.named("A", "B"))
    with pytest.raises(ValueError, match="built for none"):
        jointset.check(jointset.named("P"), jointset.NONE)
    with pytest.raises(ValueError, match="no joint 'Q'"):
        jointset.named("A", "Q")
    jointset.check(jointset.NONE, jointset.ALL)
    jointset.check(jointset.named("B"), jointset.named("A", "B"))


def test_the_device_launch_refuses_a_case_outside_its_build():
    """The CUDA batch checks its cases' sets against its kernel's before it launches."""
    from clearsweep.core import device

    with pytest.raises(ValueError, match="clearance at O cannot run on the kernel built for A,B"):
        device.launch({}, "aos", jointset.named("A", "B"), [jointset.named("O")])


@pytest.mark.parametrize("overrides, build", [(SETS[2][0], ("A", "B")), (SETS[0][0], None)],
                         ids=["A,B on the build of A and B", "ideal on its own build"])
def test_a_case_on_its_own_build_equals_the_generic_build(overrides, build):
    """Folding the absent joints away changes no arithmetic of the others: every array the
    kernel returns is the generic build's (every joint tested at run time) bit for bit, on
    the case's CPU build (params.build_of) and on the build of its joints alone (the
    device's)."""
    cfg, packed = _packed(("initial.joints=centred", "wear.amplification=1000", *overrides))
    own = run_kernel(packed, build=None if build is None else jointset.named(*build))
    generic = run_kernel(packed, build=jointset.ALL)
    assert own.status == generic.status == "ok"
    for name in ("y", "d", "wmax", "wmap", "proj", "wvol", "stats", "sec", "first_impact"):
        assert np.array_equal(getattr(own, name), getattr(generic, name), equal_nan=True), name
    assert (own.rk4_steps, own.residual_max, own.ke_peak) == (
        generic.rk4_steps, generic.residual_max, generic.ke_peak)
    assert (kernel_build(cfg) if build is None else jointset.named(*build)) != jointset.ALL


#: A second process runs the two-clearance case and says whether integrate came from the
#: on-disk cache, and under which signature.
CACHED = """
from clearsweep.config import DEFAULTS
from clearsweep.core.rk4 import integrate
from clearsweep.simulation import simulate
simulate(DEFAULTS.replace("joints.A.clearance=2.5e-4", "joints.B.clearance=2.5e-4",
                          "solver.duration=1e-4"))
print(sorted(str(sig[-1]) for sig in integrate.stats.cache_hits))
print(sorted(str(sig[-1]) for sig in integrate.stats.cache_misses))
"""


def test_the_cache_keeps_one_build_per_joint_set():
    """Numba's cache key is the signature, whose last type is the joint set as a literal:
    the build for A and B is on disk once compiled, a second process loads it (no compile),
    and another set's build is another entry."""
    from clearsweep.core.rk4 import integrate
    from clearsweep.simulation import kernel_needs_compiling

    _, packed = _packed(SETS[2][0], duration=1e-4)
    run_kernel(packed)
    build = build_of(jointset.named("A", "B"))
    assert not kernel_needs_compiling("rk4", build)
    index = integrate._cache._cache_file._load_index()
    assert any(getattr(key[0][-1], "literal_value", None) == build for key in index)
    proc = subprocess.run([sys.executable, "-c", CACHED], capture_output=True, text=True,
                          cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)}, timeout=600)
    assert proc.returncode == 0, proc.stderr
    hits, misses = proc.stdout.strip().splitlines()[-2:]
    assert hits == f"['Literal[int]({build})']"
    # run_kernel hands the set as a jointset.Build, typed as the literal at once: no int64
    # signature typed first and retried by numba.literally (18 ms a call)
    assert misses == "[]"
