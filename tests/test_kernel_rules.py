"""Each rule of the kernel is defined once (docs/architecture.md, "The kernel"), and the
places that used to repeat it now call that one definition.

- the coating/base switch: ``contact.surface``;
- the worn-socket read (bin or bilinear): ``wear.worn_surface``, also behind the seated start;
- the damping set-up of a contact: ``contact.contact_damping``;
- the bin geometry: ``wear.bin_area``, also behind service_life's bin areas;
- the end-of-run wear flush: ``rk4.flush_all_wear``, for both integrators.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from clearsweep.config import load_config, resolve_materials
from clearsweep.core import layout as L
from clearsweep.core.contact import contact_damping, damping_factor, surface
from clearsweep.core.rk4 import flush_all_wear
from clearsweep.core.wear import bin_area, map_bin, map_interp, worn_surface
from clearsweep.params import pack, worn_contact
from clearsweep.service_life import bin_areas

PACKAGE = Path(__file__).resolve().parent.parent / "clearsweep"


def sources():
    return {p.relative_to(PACKAGE).as_posix(): p.read_text() for p in PACKAGE.rglob("*.py")}


@pytest.mark.parametrize("pattern, allowed", [
    # the base material's values are read by the switch only (params packs them)
    (r"J_(EW|MU|K)_BASE\b", {"core/layout.py", "core/contact.py", "params.py"}),
    # the contact's damping is set up in one place
    (r"\bdamping_factor\(", {"core/contact.py"}),
    # the map is read (bin or bilinear) in one place
    (r"\bmap_interp\(", {"core/wear.py"}),
    (r"\bmap_bin_near\(|S_HINT_", {"core/wear.py", "core/layout.py"}),
    (r"\bworn_surface\(", {"core/wear.py", "core/spherical.py", "params.py"}),
    # bin areas come from one formula
    (r"def bin_area\b", {"core/wear.py"}),
    # the coating thickness is compared with the depth in one place
    (r">= coat\b|>= jp\[.*J_COAT\]", {"core/wear.py"}),
    # the kernel tests a joint's clearance in one place, the build's joint set first
    # (jointset.has_clearance: a compile-time constant that folds an absent joint away);
    # the host reads the packed flags where it packs and reports
    (r"J_CLEARANCE\]\s*[!=]=", {"core/jointset.py", "params.py", "simulation.py", "service_life.py"}),
    # likewise whether a joint is a bushing (jointset.is_bushing: the kernel's one switch
    # between a joint's own type and the bushing); the host where it packs, bounds the step
    # and reports
    (r"J_BUSHING\]\s*[!=]=", {"core/jointset.py", "params.py", "simulation.py"}),
])
def test_a_rule_is_written_in_one_module(pattern, allowed):
    found = {name for name, text in sources().items() if re.search(pattern, text)}
    assert found <= allowed, f"{pattern} also in {sorted(found - allowed)}"


def packed_case(overrides=()):
    cfg = load_config({"joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4}},
                       "wear": {"map": [12, 24]}}, list(overrides))
    return pack(cfg, resolve_materials(cfg))


def test_the_switch_gives_the_base_values_where_the_coating_is_worn_through():
    jp = packed_case(["joints.B.coating=PTFE"]).jp
    assert surface(jp, 1, False) == (jp[1, L.J_EW], jp[1, L.J_MU], jp[1, L.J_K])
    assert surface(jp, 1, True) == (jp[1, L.J_EW_BASE], jp[1, L.J_MU_BASE], jp[1, L.J_K_BASE])
    assert jp[1, L.J_EW_BASE] > jp[1, L.J_EW]      # PTFE is softer than the steel base


def test_worn_through_is_where_the_bin_reaches_the_coating():
    wmap = np.zeros((2, 12, 24))
    n = (1.0, 0.0, 0.0)
    ip, ia = map_bin(n, 12, 24)
    wmap[1, ip, ia] = 1e-4
    assert worn_surface(wmap, 1, n, 1e-4, True, False)[2]
    assert not worn_surface(wmap, 1, n, 1e-4 * (1 + 1e-12), True, False)[2]
    assert not worn_surface(wmap, 1, n, math.inf, True, False)[2]


def test_the_seated_start_reads_the_worn_socket_as_the_kernel_does():
    """With wear.interpolate the seated start's clearance is the bilinear one the run uses
    (it used to read the bin, a different clearance from the kernel it starts)."""
    pk = packed_case(["wear.interpolate=true", "joints.B.coating=MoS2"])
    rng = np.random.default_rng(5)
    wmap = rng.random((2, 12, 24)) * 2e-5
    n = np.array([0.6, -0.3, math.sqrt(1 - 0.45)])
    c_eff, ew = worn_contact(pk.jp, 1, wmap, n, pk.p)
    h, _ = map_interp(wmap, 1, tuple(n))
    ip, ia = map_bin(tuple(n), 12, 24)
    assert c_eff == pk.jp[1, L.J_C] + h
    assert c_eff != pk.jp[1, L.J_C] + wmap[1, ip, ia]
    assert ew == pk.jp[1, L.J_EW]                  # 20 um < 0.1 mm of MoS2: not worn through
    pk_bin = packed_case(["joints.B.coating=MoS2"])
    assert worn_contact(pk_bin.jp, 1, wmap, n, pk_bin.p)[0] == pk_bin.jp[1, L.J_C] + wmap[1, ip, ia]
    deep = np.full((2, 12, 24), 2e-4)
    assert worn_contact(pk.jp, 1, deep, n, pk.p)[1] == pk.jp[1, L.J_EW_BASE]


@pytest.mark.parametrize("dv0, ddot, expected_dv0", [
    (0.0, 0.05, 0.05),      # the episode begins in this step: the evaluation's own rate
    (0.0, -0.2, 1e-2),      # ... floored
    (0.3, 0.05, 0.3),       # an episode under way: its impact velocity
])
def test_damping_of_a_contact(dv0, ddot, expected_dv0):
    p = packed_case().p
    assert contact_damping(dv0, ddot, p) == damping_factor(p[L.P_HYST_NUM], p[L.P_HYST_DEN], expected_dv0)
    assert p[L.P_DV0_MIN] == 1e-2


@pytest.mark.parametrize("shape", [(12, 24), (36, 72), (144, 288)])
def test_bins_tile_the_sphere(shape):
    r = 0.015
    areas = bin_areas(shape, r)
    assert areas.sum() == pytest.approx(4 * math.pi * r * r, rel=1e-12)
    assert areas[3, 5] == bin_area(3, shape[0], shape[1], r)
    # symmetric about the equator
    np.testing.assert_allclose(areas, areas[::-1], rtol=1e-9)


def test_the_flush_spreads_every_waiting_cap_and_keeps_its_volume():
    wmap = np.zeros((L.N_JOINTS, 36, 72))
    pend = np.zeros((L.N_JOINTS, 6))
    vol = 3e-15
    n = np.array([0.0, 0.6, 0.8])
    pend[1, :3] = vol * n           # sum V n
    pend[1, 3] = vol                # sum V
    pend[1, 4] = vol * 2e-7         # sum V A: a cap of 0.2 mm^2
    pend[1, 5] = 0.015              # R_i
    wmax = np.zeros(L.N_JOINTS)
    flush_all_wear(wmap, pend, wmax, np.zeros((4 * 36, 3)))
    assert not pend.any()
    assert wmap[0].sum() == 0.0
    assert wmax[1] == wmap[1].max() > 0.0
    assert (wmap[1] * bin_areas((36, 72), 0.015)).sum() == pytest.approx(vol, rel=1e-12)


def kernel_dispatchers():
    """{"module.function": dispatcher} of every compiled function defined in clearsweep.core."""
    import importlib
    import pkgutil

    from numba.core.registry import CPUDispatcher

    import clearsweep.core as core

    found = {}
    for info in pkgutil.iter_modules(core.__path__):
        module = importlib.import_module(f"clearsweep.core.{info.name}")
        for name, obj in vars(module).items():
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__:
                found[f"{info.name}.{name}"] = obj
    return found


def test_kernel_functions_are_compiled_without_reference_counting():
    """The compile options are one rule too (core/compiled.py): every kernel function runs
    without Numba's runtime, whose atomic reference counts on every call cost half of the run
    time, except the entry points that allocate their work arrays."""
    from clearsweep.core.compiled import ALLOCATING

    found = kernel_dispatchers()
    assert len(found) > 80 and {"dynamics.evaluate", "rk4.advance", "spherical.contact"} <= set(found)
    assert ALLOCATING <= set(found)
    with_runtime = sorted(name for name, disp in found.items()
                          if disp.targetoptions.get("_nrt", True))
    assert with_runtime == sorted(ALLOCATING)


def test_kernel_functions_are_cached_on_disk():
    """Both decorators of the kernel cache the machine code (cache=True), so that a new
    process starts without compiling."""
    from numba.core.caching import NullCache

    uncached = sorted(name for name, disp in kernel_dispatchers().items()
                      if isinstance(disp._cache, NullCache))
    assert uncached == []


#: The most arguments a kernel function takes: its arrays go by name in named tuples
#: (core/work.py), not one argument each (advance took 43 before).
MAX_KERNEL_ARGUMENTS = 12


def test_kernel_functions_take_their_arrays_by_name():
    import inspect

    wide = sorted(f"{name} ({n})" for name, disp in kernel_dispatchers().items()
                  if (n := len(inspect.signature(disp.py_func).parameters)) > MAX_KERNEL_ARGUMENTS)
    assert wide == [], f"more than {MAX_KERNEL_ARGUMENTS} arguments: {wide}"


def test_a_step_attempt_is_compiled_into_advance():
    """``rk4.attempt_step`` is inlined into ``rk4.advance`` at Numba's level: left a call of
    its own (as when ``advance`` was split) the RK4 step ran 5-7 % fewer steps per CPU second
    on every case (benchmarks/README.md, "The CPU's grouping, measured again"). Its
    ``step_end`` and ``stage`` come from ``advance``, whose locals type them as plain
    booleans: inlining drops the callee's own locals, and as literals they would compile
    ``evaluate`` once per value of ``full`` besides, about twice a build's cold compile."""
    import inspect

    from numba import types

    from clearsweep.core import rk4

    assert rk4.attempt_step.targetoptions.get("inline") == "always"
    assert list(inspect.signature(rk4.attempt_step.py_func).parameters)[-2:] == ["step_end", "stage"]
    assert not rk4.attempt_step.locals
    local_types = rk4.advance.locals
    assert local_types["step_end"] == local_types["stage"] == types.boolean


def test_kernel_functions_divide_without_a_zero_check():
    """Every kernel function compiles float division with numpy's error model
    (core/compiled.py): no test of each divisor for zero and no raise path behind it, which
    cost the one-clearance case about 2.5 % of its steps per CPU second (benchmarks/README.md,
    "Issue 42's CPU goals, measured again"). A division by zero gives inf or NaN, which the
    step's checks stop as a non-finite state (layout.ST_NONFINITE), where it raised
    ZeroDivisionError; a run without one computes the same values to the bit."""
    from clearsweep.core.compiled import ALLOCATING
    from clearsweep.core.multibody import chol_solve

    # the allocating entry points (plain njit) divide nothing themselves: they allocate
    # and call the step
    python_model = sorted(name for name, disp in kernel_dispatchers().items()
                          if disp.targetoptions.get("error_model", "python") != "numpy")
    assert python_model == sorted(ALLOCATING)
    vz = np.ones((8, 10))
    chol_solve(np.zeros((10, 10)), vz, 0, 2)      # a zero pivot: no ZeroDivisionError
    assert not np.isfinite(vz[0, :2]).any()
