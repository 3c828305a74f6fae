"""The joint types' host side (clearsweep/jointtypes.py, params.HOST_HOOKS): every registered
type has its entry in both, and no host module branches on a type's name (compares a value
with one), so that a new type is its entries and not edits across the package."""

import ast
from pathlib import Path

import pytest

from clearsweep import jointtypes, params
from clearsweep.core import joints
from clearsweep.core import layout as L

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "clearsweep"


def type_name_comparisons(source: str, names) -> list[int]:
    """Line numbers of the comparisons in ``source`` whose operands hold one of ``names``
    as a string constant (``x == "prismatic"``, ``kind in ("revolute", "prismatic")``)."""
    names = set(names)

    def holds(node) -> bool:
        if isinstance(node, ast.Constant):
            return node.value in names
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return any(holds(e) for e in node.elts)
        return False

    return [node.lineno for node in ast.walk(ast.parse(source))
            if isinstance(node, ast.Compare) and any(holds(o) for o in (node.left, *node.comparators))]


def host_modules():
    return sorted(p for p in PACKAGE.rglob("*.py") if "core" not in p.relative_to(PACKAGE).parts)


def test_every_registered_type_has_its_host_entries():
    assert list(jointtypes.KINDS) == list(joints.JOINT_TYPES)
    assert list(params.HOST_HOOKS) == list(joints.JOINT_TYPES)
    for name, kind in jointtypes.KINDS.items():
        assert kind.name == name
        assert kind.orbit_gap in jointtypes.ORBIT_GAPS, name
        assert kind.wear_figure in jointtypes.WEAR_FIGURES, name
        # the packed columns it names are the layout's
        assert all(isinstance(getattr(L, col, None), int) for col in kind.columns), name


@pytest.mark.parametrize("path", host_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_no_host_module_branches_on_a_type_name(path):
    found = type_name_comparisons(path.read_text(), joints.JOINT_TYPES)
    assert not found, (f"{path.relative_to(ROOT)} compares with a joint type's name at lines "
                       f"{found}: look the type's behaviour up in jointtypes.KINDS or "
                       "params.HOST_HOOKS")


def test_the_branch_check_finds_a_branch():
    """The check reads comparisons, not dict keys or text."""
    names = ("prismatic", "revolute")
    assert type_name_comparisons('if kind == "prismatic":\n    pass\n', names) == [1]
    assert type_name_comparisons('x = kind in ("revolute", "prismatic")\n', names) == [1]
    assert type_name_comparisons('x = {"prismatic": 1}\ny = "a revolute joint"\n', names) == []


def test_the_gpu_batch_rows_follow_the_types():
    """The device batch's map, projection and undo rows per joint, from the types: the
    sockets' and the guide's maps take npolar rows, the bearing's one; the guide's wear has
    no projections and is not undone row by row."""
    from clearsweep import gpu

    assert {name: rows(36) for name, rows in gpu.MAP_ROWS.items()} == {
        "A": 36, "B": 36, "O": 1, "P": 36}
    assert gpu.PROJ_ROWS == {"A": 3, "B": 3, "O": 3, "P": 0}
    assert gpu.UNDO_JOINTS == ("A", "B", "O")


def test_a_recorded_type_wins_over_the_table(monkeypatch):
    """A dataset that records a joint's type (``joint_<J>_type``) is read by it: a new type
    registered as one entry (no wear, no gap) is what the figures see for that joint."""
    from clearsweep.plotting.common import joint_kind, joint_name

    bushing = jointtypes.JointKind(
        name="bushing", centre="bushing", surface="", title="bushing", force_on="the ball",
        orbit_gap="none", wear_figure="none", wear_profile=False, equal_bins=False,
        map_rows=lambda npolar: 0, proj_rows=0, undo_rows=False, axial_ideal=False,
        power_law=False, contact_law="spring-damper", columns=())
    monkeypatch.setitem(jointtypes.KINDS, "bushing", bushing)   # type: ignore[index]
    attrs = {"joint_O_type": "bushing"}
    assert jointtypes.type_of("O", attrs) == "bushing"
    assert jointtypes.type_of("O") == "revolute"
    assert jointtypes.type_of("A", attrs) == "spherical"
    assert jointtypes.kind_of("Z") is None and jointtypes.describe("Z").name == "spherical"

    class Data:
        pass

    ds = Data()
    ds.attrs = attrs
    assert joint_kind(ds, "O").wear_figure == "none"
    assert joint_name("P") == "guide P" and joint_name("O") == "bearing O"


def test_every_packed_column_is_common_or_one_types():
    """Each per-joint column of the layout is one of the common ones or named by the types
    that fill it (``JointKind.columns``), and a joint's row holds 0 in every column its type
    does not name: no column means one thing for one type and another for the next (a
    guide's corner radius and block length have their own columns, not the socket's radius
    and the bearing's length)."""
    from clearsweep.config import DEFAULTS, resolve_materials

    names = {k for k, v in vars(L).items() if k.startswith("J_") and isinstance(v, int)}
    assert sorted(getattr(L, k) for k in names) == list(range(L.N_JP))
    owned = {c for kind in jointtypes.KINDS.values() for c in kind.columns}
    assert owned <= names
    assert set(jointtypes.COMMON_COLUMNS) == names - owned
    cfg = DEFAULTS.replace(joints__A__clearance=1e-4, joints__B__clearance=1e-4,
                           joints__O__clearance=1e-4, joints__P__clearance_y=1e-4,
                           joints__P__clearance_z=2e-4)
    jp = params.pack(cfg, resolve_materials(cfg), seat=False).jp
    for j, joint in enumerate(joints.JOINTS):
        own = jointtypes.KINDS[joint.type].columns
        for col in sorted(owned - set(own)):
            assert jp[j, getattr(L, col)] == 0.0, (joint.name, col)
        assert all(jp[j, getattr(L, col)] != 0.0 for col in own if col != "J_FILM"), joint.name
        # the common columns are every type's: filled in every row with a clearance
        assert all(jp[j, getattr(L, col)] != 0.0 for col in jointtypes.COMMON_COLUMNS), joint.name
    P = joints.INDEX["P"]
    assert jp[P, L.J_C] == 1e-4 and jp[P, L.J_CORNER_RADIUS] == cfg.joints.P.corner_radius
    assert jp[P, L.J_BLOCK_LENGTH] == cfg.joints.P.block[0]


def test_the_architecture_page_lists_every_packed_column():
    text = (ROOT / "docs" / "architecture.md").read_text()
    missing = [k for k, v in vars(L).items() if k.startswith("J_") and isinstance(v, int)
               and f"`{k}`" not in text]
    assert not missing, f"docs/architecture.md's packed-column table lacks {missing}"
