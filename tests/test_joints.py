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
from clearsweep.core import joints, revolute
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


#: The module of the protocol functions that several types share (core/shared.py), which a
#: type takes by name rather than compiling a copy.
SHARED = "clearsweep.core.shared"


def unprovided(module):
    """The functions of ``joints.PROVIDES`` that a joint-type module does not provide: one
    that is missing or not compiled, or compiled elsewhere than in the module itself or in
    core/shared.py (another type's, say)."""
    out = []
    for name in joints.PROVIDES:
        obj = getattr(module, name, None)
        if not (isinstance(obj, CPUDispatcher)
                and obj.py_func.__module__ in (module.__name__, SHARED)):
            out.append(name)
    return out


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
    contacts = getattr(module, "CONTACTS", None)
    assert isinstance(contacts, int) and contacts >= 0, (
        f"core/{module_name}.py does not say how many contact points it has (CONTACTS)")
    if contacts == 0:
        # only a type that never touches may have none: it does not wear either and says
        # so (tests/test_bushing.py: the bushing's gap reports no penetration)
        assert "does not wear" in (module.__doc__ or ""), (
            f"core/{module_name}.py has no contact points without saying it does not wear")
    missing = unprovided(module)
    assert not missing, f"core/{module_name}.py does not compile or share {missing}"
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
    revolute's did), whose contact takes the block alone (as prismatic's did) or whose seat
    takes the block without the diagnostics (as prismatic's did) is named, and so is every
    protocol function it lacks; one that copies a registered type's functions is not."""
    def gap(jp, j, wmap, p, pb, ps):
        return 0.0

    def contact(j, model, slider, full, dg):
        return 0.0

    def seat(j, model, slider):
        return True

    spherical = importlib.import_module("clearsweep.core.spherical")
    wrong = types.ModuleType("wrong")
    for name in joints.PROVIDES:
        setattr(wrong, name, getattr(spherical, name))
    wrong.gap = compiled(gap)
    wrong.contact = compiled(contact)
    wrong.seat = compiled(seat)
    found = protocol_mismatches(wrong)
    assert len(found) == 3
    assert found[0].startswith("gap(jp, j, wmap, p, pb, ps) is not")
    assert found[1].startswith("contact(j, model, slider, full, dg) is not")
    assert found[2] == "seat(j, model, slider) is not seat(j, model, dg, body)"
    missing = types.ModuleType("missing")
    missing.gap = gap           # not compiled, and nothing else
    assert protocol_mismatches(missing) == [f"{name}: not a compiled function"
                                            for name in joints.PROVIDES]
    copied = types.ModuleType("copied")
    for name in joints.PROVIDES:
        setattr(copied, name, getattr(spherical, name))
    assert protocol_mismatches(copied) == []


def test_a_type_provides_each_function_itself_or_from_the_shared_module():
    """A type module may take a protocol function from core/shared.py by name; one that
    lacks a function, holds it uncompiled, or takes another type's is named."""
    from clearsweep.core import prismatic, shared, spherical

    def like_spherical():
        module = types.ModuleType(spherical.__name__)
        for name in joints.PROVIDES:
            setattr(module, name, getattr(spherical, name))
        return module

    assert unprovided(like_spherical()) == []
    assert spherical.accept is shared.neutral_accept          # shared, not a copy
    lacking = like_spherical()
    del lacking.seat
    lacking.penetration = spherical.penetration.py_func      # not compiled
    lacking.accept = prismatic.accept                        # another type's
    assert unprovided(lacking) == ["accept", "penetration", "seat"]


def protocol_bodies(module):
    """The protocol functions that ``module`` compiles itself, as (protocol name, its
    body's AST as text, docstring dropped): a type module's under the protocol's names,
    core/shared.py's under ``<group>_<name>``."""
    import ast

    out = []
    for attr, obj in vars(module).items():
        if not (isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__):
            continue
        name = next((f for f in joints.PROVIDES if attr == f or attr.endswith("_" + f)), None)
        if name is None or (attr != name and module.__name__ != SHARED):
            continue
        body = ast.parse(inspect.cleandoc("\n" + inspect.getsource(obj.py_func))).body[0].body
        if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
            body = body[1:]
        out.append((name, "".join(ast.dump(node) for node in body)))
    return out


def copies(modules):
    """Protocol functions written twice: the same protocol function with the same body
    compiled in two places (modules' names, the function's name)."""
    seen: dict = {}
    found = []
    for module in modules:
        for name, body in protocol_bodies(module):
            if (name, body) in seen:
                found.append(f"{name}: {seen[name, body]} and {module.__name__}")
            seen.setdefault((name, body), module.__name__)
    return found


def _copied_accept(j, model, body, hs, in_settled, stats, cur):
    """A copy of the neutral accept, written again."""
    return False


def test_no_protocol_function_is_written_twice():
    """The joint types' protocol functions and core/shared.py's: no two are the same
    function with the same body (a type takes the shared one by name instead); a type
    that compiles a copy of a shared function is named."""
    from clearsweep.core import shared

    modules = [importlib.import_module(f"clearsweep.core.{name}")
               for name in sorted(set(joints.JOINT_TYPES.values()))]
    assert copies(modules + [shared]) == []
    copied = types.ModuleType(__name__)
    copied.accept = compiled(_copied_accept)
    copied.accept.py_func.__name__ = "accept"
    assert copies([shared, copied]) == [f"accept: {SHARED} and {__name__}"]


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


#: Vector results of the protocol (3-tuples), by function.
VECTORS = {"section_offsets": ("offset", "offset_rate"),
           "rate_point": ("offset_ball", "offset_socket")}


def protocol_arguments(module, j, pk, model, body):
    """Arguments of each protocol function besides gap and contact for joint row j of a
    type module, at the packed start: a contact 0.1 um deep at the normal (0, 0.6, 0.8)."""
    jp = pk.jp
    pen = 1e-7
    e = jp[j, L.J_C] + pen
    n = (0.0, 0.6, 0.8)
    area, *_, scale = module.wear_surface(jp, j, pen, e, n)
    if not area > 0.0:
        area, scale = 1e-7, 1.0
    wmap = np.zeros((L.N_JOINTS, 36, 72))
    cur = np.zeros((L.N_CAP_ROWS, L.N_CAP))
    dg = np.zeros(L.N_D)
    dg[L.D_DELTA + j], dg[L.D_DDOT + j], dg[L.D_ECC + j] = pen, 0.01, e
    dg[L.D_NGLOBAL + 3 * j:L.D_NGLOBAL + 3 * j + 3] = n
    dg[L.D_PRATE] = 1.25e5
    # the mobility of a 2 kg point free in every direction
    wp = (0.5, 0.0, 0.0, 0.5, 0.0, 0.5)
    return {
        "elastic_law": (pk.p, j),
        "paper_angle": (jp, j, pen, e),
        "wear_surface": (jp, j, pen, e, n),
        "cap_mergeable": (j, 1e-6, 0.05, area, scale),
        "deposit_cap": (wmap, j, n, 1e-15, area, scale, np.zeros((4 * 36, 3))),
        "accept": (j, model, body, 1e-5, False, np.zeros((L.N_WINDOWS, L.N_M)), cur),
        "deposit_step": (wmap, j, jp, cur, np.zeros(L.N_JOINTS)),
        "penetration": (j, model, 0, body),
        "section_offsets": (jp, j, (1e-5, 2e-5, 3e-5), (0.1, 0.2, 0.3)),
        "seat": (j, model, dg, body),
        "rate_point": (j, model, dg),
        "force_rate": (j, model, dg, wp, pk.y0, pk.p[L.P_EXPONENT]),
    }


def test_every_joint_types_protocol_returns_its_shape_and_neutral_values():
    """Each registered type's protocol functions besides gap and contact, on a joint of its
    type (the bushing on joint A, which it may stand in for) at the packed start: a tuple
    of the length ``joints.PROTOCOL`` names (a single value where it names one), 3-vectors
    where named; a one-point type's multi-contact functions and a multi-contact type's
    one-point ones return their neutral values."""
    from clearsweep.core.jointkinds import ball_body

    cfg = DEFAULTS.replace(joints__A__clearance=1e-4, joints__B__clearance=1e-4,
                           joints__O__clearance=1e-4, joints__P__clearance_y=1e-4,
                           joints__P__clearance_z=1e-4)
    pk = pack(cfg, resolve_materials(cfg))
    spec = {fn.name: fn for fn in joints.PROTOCOL}
    rows = {joint.type: j for j, joint in reversed(list(enumerate(joints.JOINTS)))}
    for type_name, module_name in sorted(joints.JOINT_TYPES.items()):
        module = importlib.import_module(f"clearsweep.core.{module_name}")
        j = rows.get(type_name, 0)
        model = Model(pk.p, pk.jp, np.zeros((L.N_JOINTS, L.N_S)), np.zeros((L.N_JOINTS, 36, 72)))
        args = protocol_arguments(module, j, pk, model, ball_body(j, pk.y0))
        assert set(args) | {"gap", "contact"} == set(joints.PROVIDES)
        out = {}
        for name, arg in args.items():
            got = getattr(module, name)(*arg)
            out[name] = got
            if len(spec[name].returns) == 1:
                assert not isinstance(got, tuple), (type_name, name)
            else:
                assert isinstance(got, tuple) and len(got) == len(spec[name].returns), (
                    type_name, name)
                for vec in VECTORS.get(name, ()):
                    assert len(got[spec[name].returns.index(vec)]) == 3, (type_name, name)
        if module.CONTACTS == 1:
            assert out["accept"] is False and out["deposit_step"] == 0.0, type_name
            assert out["penetration"] == -np.inf and out["seat"] is True, type_name
            assert out["wear_surface"][0] > 0.0 and out["deposit_cap"] > 0.0, type_name
            c = pk.jp[j, L.J_C]
            assert out["section_offsets"] == ((1e-5 / c, 2e-5 / c, 3e-5 / c),
                                              (0.1 / c, 0.2 / c, 0.3 / c)), type_name
            # the contact points at the radii along the normal, due in contact; rated on
            # their mobility: the approach's reachable penetration gives a positive rate
            assert out["rate_point"] == (True, True, tuple(pk.jp[j, L.J_RJ] * np.array(
                (0.0, 0.6, 0.8))), tuple(pk.jp[j, L.J_RI] * np.array((0.0, 0.6, 0.8)))), type_name
            assert out["force_rate"] > 0.0, type_name
        elif module.CONTACTS > 1:
            assert out["wear_surface"] == (0.0,) * 5 and out["deposit_cap"] == 0.0, type_name
            assert out["paper_angle"] == (np.pi, False), type_name
            assert np.isfinite(out["penetration"]) and out["section_offsets"][0][0] == 0.0
            # the guide's rate is its corners' own, stored by its contact
            assert out["rate_point"] == (True, False, (0.0,) * 3, (0.0,) * 3), type_name
            assert out["force_rate"] == 1.25e5, type_name
        else:
            assert out["seat"] is False and out["accept"] is False, type_name
            assert np.isnan(out["section_offsets"][0]).all(), type_name
            # a bushing's rate is always due, at its centres themselves
            assert out["rate_point"] == (True, True, (0.0,) * 3, (0.0,) * 3), type_name


def test_the_dispatch_reads_each_rows_type_and_ball_body_from_the_table():
    """jointkinds' masks put each row of the table under its own type alone (in the RSSP's
    builds the table's type, in the slider-crank's its own: A and B revolute), its
    multi-contact rows are those whose type has several contact points, and a row's ball
    body state is the one its body's slots of joints.BODIES give (for the guide's block, bit
    for bit the state dynamics.evaluate hands the guide's contact)."""
    from clearsweep.core import jointkinds as kinds
    from clearsweep.core import jointset
    from clearsweep.core.dynamics import slider_state

    for spec, slider_crank in ((jointset.ALL, False), (jointset.ALL | jointset.SLIDER_CRANK, True)):
        masks = {"spherical": kinds.spherical_rows(spec), "revolute": kinds.revolute_rows(spec),
                 "prismatic": kinds.prismatic_rows(spec), "bushing": kinds.BUSHING}
        assert set(masks) == set(joints.JOINT_TYPES) == set(kinds.MODULES)
        types = joints.row_types(slider_crank)
        for j, joint in enumerate(joints.JOINTS):
            assert [t for t, m in masks.items() if kinds.of_kind(m, j)] == [types[j]], joint.name
            # the elastic law the stiff rate reads (its force_rate): a journal's own
            # where the case keeps the paper's, the case's for every other type
            for exponent in (0.0, 1.5, 1.0):
                p = np.zeros(L.N_P)
                p[L.P_EXPONENT] = exponent
                law = kinds.elastic_law(spec, p, j)
                if types[j] == "revolute":
                    assert law == (exponent or revolute.JOURNAL_EXPONENT), joint.name
                else:
                    assert law == exponent, joint.name
            module = importlib.import_module(f"clearsweep.core.{joints.JOINT_TYPES[types[j]]}")
            assert kinds.is_multi(j) == (module.CONTACTS > 1)
            assert kinds.contacts(spec, j) == module.CONTACTS
            assert (kinds.MULTI_ROW == j) == (module.CONTACTS > 1), joint.name
    assert joints.row_types(False) == tuple(joint.type for joint in joints.JOINTS)
    assert joints.row_types(True) == ("revolute", "revolute", "revolute", "prismatic")
    rng = np.random.default_rng(3)
    y = rng.normal(scale=0.1, size=L.N_Y)
    bodies = {b.name: b for b in joints.BODIES}
    for j, joint in enumerate(joints.JOINTS):
        body = bodies[joint.ball.body]
        r, v, R, w = kinds.ball_body(j, y)
        assert r == tuple(y[body.y_r:body.y_r + 3]), joint.name
        assert v == tuple(y[L.Y_QD + body.y_r:L.Y_QD + body.y_r + 3]), joint.name
        assert R == rotation(trig(*y[body.y_phi:body.y_phi + 3])), joint.name
        if body.name == "slider":
            assert (r, v, R, w) == slider_state(y)


def test_the_dispatchers_are_made_from_the_protocol_and_call_each_rows_function():
    """Each dispatcher of jointkinds is made by its factory from ``joints.PROTOCOL``: it takes
    the build's joint set and the protocol's parameters, tests one mask per distinct function
    the types provide (the types that share core/shared.py's function tested together, the
    bushing's the fall-through), and returns for each row of either mechanism what that
    row's type's own function returns."""
    from clearsweep.core import jointkinds as kinds
    from clearsweep.core import jointset, shared

    for fn in joints.PROTOCOL[2:]:
        dispatch = getattr(kinds, fn.name)
        assert tuple(inspect.signature(dispatch.py_func).parameters) == ("spec", *fn.params)
        source, scope = kinds.dispatch_source(fn.name)
        distinct = {id(getattr(m, fn.name)) for m in kinds.MODULES.values()}
        assert source.count("if of_kind(") == len(distinct) - 1, fn.name
        assert {id(f) for f in scope.values()} == distinct, fn.name
    # the contact dispatcher's types are the one-point ones, and every row whose contact
    # dynamics applies through it (all but the multi-contact row) is of one of them
    assert kinds.ONE_POINT == tuple(k for k, m in kinds.MODULES.items() if m.CONTACTS == 1)
    assert "prismatic" not in kinds.dispatch_source("contact", kinds.ONE_POINT)[0]
    for slider_crank in (False, True):
        types_ = joints.row_types(slider_crank)
        assert [t in kinds.ONE_POINT for t in types_] == [
            j != kinds.MULTI_ROW for j in range(joints.N_JOINTS)]
    accept, _ = kinds.dispatch_source("accept")
    assert "prismatic_rows(spec)" in accept and "spherical_rows" not in accept
    assert kinds.dispatch_source("accept")[1]["accept_0"] is shared.neutral_accept
    cfg = DEFAULTS.replace(joints__A__clearance=1e-4, joints__B__clearance=1e-4,
                           joints__O__clearance=1e-4, joints__P__clearance_y=1e-4,
                           joints__P__clearance_z=1e-4)
    pk = pack(cfg, resolve_materials(cfg))
    d, rate = (1e-5, 2e-5, 3e-5), (0.1, 0.2, 0.3)
    for spec, slider_crank in ((jointset.ALL, False), (jointset.ALL | jointset.SLIDER_CRANK, True)):
        for j, kind in enumerate(joints.row_types(slider_crank)):
            module = kinds.MODULES[kind]
            assert (kinds.paper_angle(spec, pk.jp, j, 1e-7, 1e-4)
                    == module.paper_angle(pk.jp, j, 1e-7, 1e-4)), (kind, j)
            assert (kinds.section_offsets(spec, pk.jp, j, d, rate)
                    == module.section_offsets(pk.jp, j, d, rate)), (kind, j)


def test_the_type_frame_turns_the_slider_cranks_guide_alone_and_back():
    """The guide's block reaches its type in the frame the type is written in: in a
    slider-crank build the guide's row sees the block turned by the rotation Q of
    ``prismatic.PLANAR_GUIDE`` (Q r, Q v, Q R Q^T, Q w: the same rigid motion) and its
    vectors come back by Q^T, exactly (Q permutes and negates); every other row, and every
    row of an RSSP build, as is. Its contact is the multi-contact types' dispatcher's, whose
    one type is called without a test."""
    from clearsweep.core import jointkinds as kinds
    from clearsweep.core import jointset, prismatic

    Q = np.asarray(prismatic.PLANAR_GUIDE).reshape(3, 3)
    assert np.array_equal(Q.T @ Q, np.eye(3)) and np.isclose(np.linalg.det(Q), 1.0)
    rng = np.random.default_rng(5)
    r, v, w = (tuple(rng.normal(size=3)) for _ in range(3))
    R = rotation(trig(*rng.normal(size=3)))
    body = (r, v, R, w)
    for spec, slider_crank in ((jointset.ALL, False), (jointset.ALL | jointset.SLIDER_CRANK, True)):
        for j, kind in enumerate(joints.row_types(slider_crank)):
            turned = slider_crank and kinds.MODULES[kind].CONTACTS > 1
            assert kinds.turns_frame(spec, j) == turned, (spec, j)
            rq, vq, Rq, wq = kinds.in_type_frame(spec, j, body)
            if turned:
                Rm = np.asarray(R).reshape(3, 3)
                assert np.array_equal(rq, Q @ r) and np.array_equal(vq, Q @ v)
                assert np.array_equal(np.asarray(Rq).reshape(3, 3), Q @ Rm @ Q.T)
                assert np.array_equal(wq, Q @ w)
            else:
                assert (rq, vq, Rq, wq) == body
            for vec in (r, v, w):
                back = kinds.from_type_frame(spec, j, vec)
                assert np.array_equal(back, Q.T @ vec if turned else vec)
                assert kinds.from_type_frame(spec, j, kinds.type_vector(spec, j, vec)) == vec
    assert kinds.MULTI_TYPES == tuple(k for k, m in kinds.MODULES.items() if m.CONTACTS > 1)
    for slider_crank in (False, True):
        assert joints.row_types(slider_crank)[kinds.MULTI_ROW] in kinds.MULTI_TYPES
    source, scope = kinds.dispatch_source("contact", kinds.MULTI_TYPES)
    assert "of_kind" not in source
    assert {id(f) for f in scope.values()} == {
        id(kinds.MODULES[k].contact) for k in kinds.MULTI_TYPES}


#: Kernel modules that dispatch on a joint's type (core/jointkinds.py) and must not name a
#: joint of the table.
NAMELESS = ("rk4.py", "dopri5.py", "wear.py", "device.py", "jointkinds.py")


def joint_mentions(source):
    """Where Python source names a joint of the table: a ``JOINT_A``/``B``/``O``/``P`` name
    (bare, an attribute or an import) or a subscript of ``INDEX`` (``joints.INDEX["P"]``)."""
    import ast
    import re

    named = re.compile(r"JOINT_[ABOP]$")
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Name) and named.match(node.id):
            found.append(f"line {node.lineno}: {node.id}")
        elif isinstance(node, ast.Attribute) and named.match(node.attr):
            found.append(f"line {node.lineno}: .{node.attr}")
        elif isinstance(node, ast.alias) and named.match(node.asname or node.name):
            found.append(f"line {node.lineno}: import {node.name}")
        elif isinstance(node, ast.Subscript):
            target = node.value
            name = target.id if isinstance(target, ast.Name) else getattr(target, "attr", None)
            if name == "INDEX":
                found.append(f"line {node.lineno}: INDEX[...]")
    return found


@pytest.mark.parametrize("name", NAMELESS)
def test_the_integrators_name_no_joint(name):
    """The integrators, the wear map, the device kernel and the type dispatch read the
    joint table through the joint-type protocol (``jointkinds``), never a joint by name."""
    source = (ROOT / "clearsweep" / "core" / name).read_text()
    assert joint_mentions(source) == [], f"core/{name} names a joint"


def test_the_scan_finds_a_joint_named_in_any_form():
    source = ("from .dynamics import JOINT_P\n"
              "def f(j, y):\n"
              "    if j == JOINT_O:\n"
              "        return dynamics.JOINT_A + joints.INDEX['P'] + INDEX['B']\n"
              "    return JOINT_Q + INDEX_P + x[JOINT_B_ROWS]\n")
    assert sorted(joint_mentions(source)) == ["line 1: import JOINT_P", "line 3: JOINT_O",
                                              "line 4: .JOINT_A", "line 4: INDEX[...]",
                                              "line 4: INDEX[...]"]


#: Kernel modules that reach the joint types through core/jointkinds.py alone.
TYPELESS = ("dynamics.py", "rk4.py", "dopri5.py", "wear.py", "device.py")


def type_module_imports(source):
    """The joint-type modules (``joints.JOINT_TYPES``' modules) that the Python source of a
    module of ``clearsweep.core`` imports, in any form: ``from . import m``, ``from .m import
    f``, ``from clearsweep.core import m``, ``import clearsweep.core.m`` (a name of another
    module, ``from .joints import JOINTS``, is none)."""
    import ast

    types_ = set(joints.JOINT_TYPES.values())
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom):
            package = "clearsweep.core" if node.level == 1 else "clearsweep" if node.level == 2 else ""
            base = ".".join(part for part in (package, node.module or "") if part)
            names = [base] + [f"{base}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        for name in names:
            parent, _, module = name.rpartition(".")
            if parent == "clearsweep.core" and module in types_:
                found.add(module)
    return found


@pytest.mark.parametrize("name", TYPELESS)
def test_the_kernel_reaches_the_joint_types_through_jointkinds(name):
    """Dynamics and the integrators import no joint-type module: each type's functions are
    reached through core/jointkinds.py's dispatch (the guide's block in
    ``dynamics.free_slider``: ``jointkinds.multi_contact`` in the frame its type is written
    in, ``in_type_frame``, ``from_type_frame``; a bushing's contact and every joint's stiff
    rate through ``jointkinds.per_case``'s ``contact``, ``rate_point`` and ``force_rate``),
    so that they call no type by name."""
    source = (ROOT / "clearsweep" / "core" / name).read_text()
    assert sorted(type_module_imports(source)) == [], f"core/{name} imports a joint type"


def test_the_import_scan_finds_a_type_module_imported_in_any_form():
    source = ("from . import jointkinds as kinds, prismatic\n"
              "from .spherical import contact\n"
              "from clearsweep.core import revolute as rv\n"
              "import clearsweep.core.bushing\n"
              "from .joints import JOINTS\n"
              "from ..core import layout\n")
    assert type_module_imports(source) == {"prismatic", "spherical", "revolute", "bushing"}
    assert type_module_imports("from ..core import prismatic\n") == {"prismatic"}
    assert type_module_imports("from .jointkinds import in_type_frame, prismatic_rows\n") == set()


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


@pytest.mark.parametrize("free", [False, True], ids=["O and P ideal", "O and P free"])
def test_the_inverse_masses_come_from_the_free_coordinates_table(free):
    """``dynamics.minv_apply`` with the inverse masses evaluate forms from ``joints.FREE``
    and ``joints.BODIES`` (``dynamics.group_inverse_mass``) puts on each centroid
    coordinate's column 1/m of the body the table names, or 0 where the table frees it by a
    joint that is ideal in the case, and nothing on another column."""
    from clearsweep.core import dynamics, jointset

    over = (["joints.O.clearance=2.5e-4", "joints.P.clearance_y=2.5e-4",
             "joints.P.clearance_z=2.5e-4"] if free else [])
    cfg = load_config({}, over)
    pk = pack(cfg, resolve_materials(cfg))
    mass = {"crank": pk.p[L.P_M2], "rod": pk.p[L.P_M3], "slider": pk.p[L.P_M4]}
    groups = dynamics.MASS_GROUPS
    minv = tuple(dynamics.group_inverse_mass(jointset.ALL, pk.p, pk.jp, k)
                 for k in range(len(groups))) + (1.0 / pk.p[L.P_M3],)
    nz = dynamics.NZ
    vz = np.zeros((2, nz))
    for k, c in enumerate(joints.FREE):
        if c.axis not in ("x", "y", "z"):
            continue
        vz[0] = 0.0
        vz[0, k] = 1.0
        dynamics.minv_apply(minv, (0.0, 0.0, 0.0, 0.0), vz, 0, 1)
        held = c.freed_by is not None and not free
        assert vz[1, k] == (0.0 if held else 1.0 / mass[c.body]), c.name
        assert np.count_nonzero(vz[1]) == (0 if held else 1), c.name
    assert dynamics.mass_groups(joints.FREE) == groups
    assert dynamics.mass_groups(joints.FREE[::-1]) != groups      # another order, other groups


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
