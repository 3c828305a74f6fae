"""The joint table (core/joints.py) and the joint types' registration: a joint-type module
that is not registered, a registration without its module, functions or docs, or a table
that disagrees with the layout, the config or the packed initial state fails here."""

import dataclasses
import importlib
import inspect
import pkgutil
import types
from pathlib import Path

import numpy as np
import pytest
from numba.core.registry import CPUDispatcher

import clearsweep.core as core
from clearsweep.config import DEFAULTS, JointsConfig, load_config, resolve_materials
from clearsweep.core import joints
from clearsweep.core import layout as L
from clearsweep.core.compiled import compiled
from clearsweep.core.kinematics import mv, rotation, trig
from clearsweep.core.work import Model
from clearsweep.params import joint_configs, pack

ROOT = Path(__file__).resolve().parent.parent


def core_modules():
    return {info.name: importlib.import_module(f"clearsweep.core.{info.name}")
            for info in pkgutil.iter_modules(core.__path__)}


def compiled_here(module, name):
    obj = getattr(module, name, None)
    return isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__


def test_every_joint_type_module_is_registered():
    """A module of core/ that declares JOINT_TYPE, or compiles a joint type's gap and
    contact, is registered under its type name."""
    for name, module in core_modules().items():
        declared = getattr(module, "JOINT_TYPE", None)
        if declared is None and not (compiled_here(module, "gap")
                                     and compiled_here(module, "contact")):
            continue
        assert declared is not None, f"core/{name}.py implements a joint type without JOINT_TYPE"
        assert joints.JOINT_TYPES.get(declared) == name, (
            f"joint type {declared!r} of core/{name}.py is not registered in "
            f"core/joints.py JOINT_TYPES")


@pytest.mark.parametrize("type_name, module_name", sorted(joints.JOINT_TYPES.items()))
def test_a_registered_joint_type_has_its_module_functions_and_docs(type_name, module_name):
    module = importlib.import_module(f"clearsweep.core.{module_name}")
    assert module.JOINT_TYPE == type_name
    wear = getattr(module, "WEAR_SURFACE", None)
    assert wear is not None, (
        f"core/{module_name}.py does not name its wear surface's functions (WEAR_SURFACE)")
    if not wear:
        # only a type that does not wear may name none: it compiles no wear geometry and
        # says so (tests/test_bushing.py: the bushing's gap reports no penetration)
        assert not any(compiled_here(module, f) for f in ("deposit", "contact_angle",
                                                          "contact_area")), (
            f"core/{module_name}.py has wear functions but names none in WEAR_SURFACE")
        assert "does not wear" in (module.__doc__ or ""), (
            f"core/{module_name}.py names no wear surface without saying it does not wear")
    missing = [f for f in (*joints.PROVIDES, *wear) if not compiled_here(module, f)]
    assert not missing, f"core/{module_name}.py does not compile {missing}"
    arch = (ROOT / "docs" / "architecture.md").read_text()
    assert f"`{module_name}.py`" in arch and f"`{type_name}`" in arch, (
        f"docs/architecture.md does not describe the joint type {type_name}")


def protocol_mismatches(module):
    """How the functions of a joint-type module differ from ``joints.PROTOCOL``: one line per
    function that is missing, not compiled, or takes other parameters (names and order)."""
    out = []
    for fn in joints.PROTOCOL:
        obj = getattr(module, fn.name, None)
        if not isinstance(obj, CPUDispatcher):
            out.append(f"{fn.name}: not a compiled function")
            continue
        params = tuple(inspect.signature(obj.py_func).parameters)
        if params != fn.params:
            out.append(f"{fn.name}({', '.join(params)}) is not "
                       f"{fn.name}({', '.join(fn.params)})")
    return out


@pytest.mark.parametrize("type_name, module_name", sorted(joints.JOINT_TYPES.items()))
def test_a_registered_joint_type_compiles_the_protocol_signatures(type_name, module_name):
    module = importlib.import_module(f"clearsweep.core.{module_name}")
    assert protocol_mismatches(module) == [], f"joint type {type_name} (core/{module_name}.py)"


def test_a_joint_type_with_another_signature_fails_the_protocol_check():
    """The check reads the parameters: a module whose gap lacks the socket's rotation (as
    revolute's did) or whose contact takes the block alone (as prismatic's did) is named;
    one that copies a registered type's functions is not."""
    def gap(jp, j, wmap, p, pb, ps):
        return 0.0

    def contact(j, model, slider, full, dg):
        return 0.0

    wrong = types.ModuleType("wrong")
    wrong.gap = compiled(gap)
    wrong.contact = compiled(contact)
    found = protocol_mismatches(wrong)
    assert len(found) == 2
    assert found[0].startswith("gap(jp, j, wmap, p, pb, ps) is not")
    assert found[1].startswith("contact(j, model, slider, full, dg) is not")
    missing = types.ModuleType("missing")
    missing.gap = gap           # not compiled, and no contact
    assert protocol_mismatches(missing) == ["gap: not a compiled function",
                                            "contact: not a compiled function"]
    copied = types.ModuleType("copied")
    spherical = importlib.import_module("clearsweep.core.spherical")
    copied.gap, copied.contact = spherical.gap, spherical.contact
    assert protocol_mismatches(copied) == []


def body_states(pk):
    """Each body's state (r, v, R, w) at the packed initial state, at rest."""
    y = pk.y0
    zero = (0.0, 0.0, 0.0)
    out = {}
    for body in joints.BODIES:
        if body.y_r is None:
            out[body.name] = (zero, zero, (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0), zero)
        else:
            R = rotation(trig(*(float(a) for a in y[body.y_phi:body.y_phi + 3])))
            out[body.name] = (tuple(float(a) for a in y[body.y_r:body.y_r + 3]), zero, R, zero)
    return out


def test_every_joint_types_functions_return_the_protocols_shape():
    """Each joint of the table, with clearance, through its type's compiled gap and contact
    at the packed initial state (the table's attachments as ball and socket): each returns
    a tuple of the length that ``joints.PROTOCOL`` names, vectors where it names them."""
    cfg = DEFAULTS.replace(joints__A__clearance=1e-4, joints__B__clearance=1e-4,
                           joints__O__clearance=1e-4, joints__P__clearance_y=1e-4,
                           joints__P__clearance_z=1e-4)
    pk = pack(cfg, resolve_materials(cfg))
    lengths = {"l2": pk.p[L.P_L2], "l3": pk.p[L.P_L3], "zs": pk.p[L.P_ZS], None: 0.0}
    states = body_states(pk)
    wmap = np.zeros((L.N_JOINTS, 36, 72))
    model = Model(pk.p, pk.jp, np.zeros((L.N_JOINTS, L.N_S)), wmap)
    spec = {fn.name: fn for fn in joints.PROTOCOL}
    for j, joint in enumerate(joints.JOINTS):
        module = importlib.import_module(f"clearsweep.core.{joints.JOINT_TYPES[joint.type]}")
        ends = []
        for att in (joint.ball, joint.socket):
            r, v, R, w = states[att.body]
            u = tuple(float(lengths[att.length]) * f for f in att.factors)
            ends.append((r, v, R, w, u))
        pb = tuple(np.add(ends[0][0], mv(ends[0][2], ends[0][4])))
        ps = tuple(np.add(ends[1][0], mv(ends[1][2], ends[1][4])))
        geo = module.gap(pk.jp, j, wmap, pk.p, 0, pb, ps, ends[1][2])
        assert len(geo) == len(spec["gap"].returns), joint.name
        for name in ("n", "d_s", "n_s", "slope"):
            assert len(geo[spec["gap"].returns.index(name)]) == 3, (joint.name, name)
        act = module.contact(j, model, ends[0], ends[1], True, np.zeros(L.N_D))
        assert len(act) == len(spec["contact"].returns), joint.name
        assert [len(v) for v in act[:3]] == [3, 3, 3] and np.isfinite(act[3]), joint.name


def test_the_table_names_registered_types_bodies_and_config_sections():
    names = [j.name for j in joints.JOINTS]
    assert len(set(names)) == len(names) == joints.N_JOINTS == L.N_JOINTS
    bodies = {b.name for b in joints.BODIES}
    for joint in joints.JOINTS:
        assert joint.type in joints.JOINT_TYPES
        assert joint.ball.body in bodies and joint.socket.body in bodies
        assert joint.ball.body != joint.socket.body
    # the config has one section per joint of the table, read in the table's order
    assert [f.name for f in dataclasses.fields(JointsConfig)] == names
    assert [name for name, _ in joint_configs(DEFAULTS)] == names


def test_per_joint_blocks_of_the_layout_follow_the_table():
    """Each per-joint block of the diagnostics and statistics is N_JOINTS (or 3 N_JOINTS)
    long, and the blocks tile the vectors without gaps or overlaps."""
    nj = L.N_JOINTS
    for prefix, total, triples in (("D_", L.N_D, {"D_JOINT_FORCE", "D_OFFSET", "D_NORMAL",
                                                   "D_NGLOBAL"}),
                                   ("M_", L.N_M, set())):
        starts = sorted((v, k) for k, v in vars(L).items() if k.startswith(prefix))
        ends = [v for v, _ in starts[1:]] + [total]
        for (start, name), end in zip(starts, ends):
            width = end - start
            if name in triples:
                assert width == 3 * nj, name
            elif width > 1 and name != "D_REACTION_O":
                assert width == nj, name
    assert L.N_R == L.R_FIRST_IMPACT + nj


def test_the_table_attachments_meet_at_the_ideal_start():
    """Each joint's ball point (on its body) and socket point (on the other) coincide at
    the packed initial state of a mechanism without clearance: the attachments of the
    table are the ones the state and the kernel are built with."""
    cfg = DEFAULTS.replace(joints__A__clearance=0.0, joints__B__clearance=0.0)
    pk = pack(cfg, resolve_materials(cfg))
    y = pk.y0
    lengths = {"l2": pk.p[L.P_L2], "l3": pk.p[L.P_L3], "zs": pk.p[L.P_ZS], None: 0.0}
    by_name = {b.name: b for b in joints.BODIES}

    def point(att):
        body = by_name[att.body]
        u = tuple(lengths[att.length] * f for f in att.factors)
        if body.y_r is None:        # the ground: at the origin, unrotated
            return np.asarray(u)
        R = rotation(trig(*y[body.y_phi:body.y_phi + 3]))
        return np.asarray(y[body.y_r:body.y_r + 3]) + np.asarray(mv(R, u))

    for joint in joints.JOINTS:
        ball, socket = point(joint.ball), point(joint.socket)
        if joint.type == "prismatic":   # the block slides along its guide, the x axis
            ball[0] = socket[0]
        assert np.allclose(ball, socket, rtol=0.0, atol=1e-12), joint.name
    # and a moved attachment would not meet
    moved = joints.JOINTS[0].ball._replace(factors=(0.0, 0.0, 0.5))
    assert not np.allclose(point(moved), point(joints.JOINTS[0].socket), atol=1e-6)


def test_the_free_coordinates_table_sizes_the_solve():
    """``joints.FREE`` describes the solve's columns: its length is ``dynamics.NZ``, the
    coordinates the guide frees come last (``NZ_HELD`` before them), and each names a body
    with a state, an axis and, where it is not always free, a joint of the table whose ball
    is that body."""
    from clearsweep.core import dynamics

    by_name = {b.name: b for b in joints.BODIES}
    names = [j.name for j in joints.JOINTS]
    assert dynamics.NZ == len(joints.FREE)
    assert [c.freed_by for c in joints.FREE[dynamics.NZ_HELD:]] == ["P", "P"]
    for c in joints.FREE:
        assert by_name[c.body].y_r is not None, c
        assert c.axis in ("x", "y", "z", "alpha", "beta"), c
        if c.freed_by is not None:
            joint = joints.JOINTS[names.index(c.freed_by)]
            assert joint.ball.body == c.body and c.axis in ("y", "z"), c


def _state_index(c):
    body = {b.name: b for b in joints.BODIES}[c.body]
    if c.axis in ("x", "y", "z"):
        return body.y_r + "xyz".index(c.axis)
    return body.y_phi + ("alpha", "beta").index(c.axis)


@pytest.mark.parametrize("free", [False, True], ids=["O and P ideal", "O and P free"])
def test_the_free_coordinates_are_the_solves_columns(free):
    """Each entry of ``joints.FREE`` is the state coordinate whose acceleration the solve
    returns in that column: evaluate's free accelerations vz[VZ_ZDD, c] are the state
    derivative's accelerations of the coordinate the table names, where the coordinate is
    free; a coordinate the table frees by a joint without clearance is held (its column's
    acceleration 0, the state's from the joint's own constraint)."""
    from clearsweep.core import dynamics
    from clearsweep.core.work import Solve

    over = (["joints.O.clearance=2.5e-4", "joints.P.clearance_y=2.5e-4",
             "joints.P.clearance_z=2.5e-4"] if free else [])
    cfg = load_config({}, ["solver.duration=0.01"] + over)
    pk = pack(cfg, resolve_materials(cfg))
    nz = dynamics.NZ
    solve = Solve(np.zeros((nz, nz)), np.zeros((nz, nz)), np.zeros((nz, nz)),
                  np.zeros((dynamics.VZ_ROWS, nz)))
    y = pk.y0.copy()
    y[L.Y_QD:L.Y_QD + L.N_Q] += 0.01 * np.sin(np.arange(L.N_Q))   # a state off the closed form
    dy = np.zeros_like(y)
    model = Model(pk.p, pk.jp, np.zeros((L.N_JOINTS, L.N_S)),
                  np.zeros((L.N_JOINTS, *pk.map_shape)))
    # full=False: a step end's diagnostics reuse vz's rows as work (the stiff rate)
    assert dynamics.evaluate(0.0, y, model, dy, np.zeros(L.N_D), False, solve) == L.ST_OK
    zdd = solve.vz[dynamics.VZ_ZDD]
    for k, c in enumerate(joints.FREE):
        if c.freed_by is None or free:
            assert zdd[k] == dy[L.Y_QD + _state_index(c)], c.name
        else:
            assert zdd[k] == 0.0, c.name
