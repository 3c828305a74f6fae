"""Configuration: defaults, normalisation, overrides, round trips and error messages."""

import copy
import dataclasses
import pickle
import re
from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

import clearsweep.config as config_module
from clearsweep.config import (
    DEFAULTS,
    MAX_YAML_ALIASES,
    MAX_YAML_BYTES,
    SCHEMA,
    Config,
    ConfigError,
    apply_override,
    dump_config,
    get_path,
    load_config,
    parse_yaml,
    radius_key,
    resolve_materials,
    section_clearance,
    set_path,
)


def leaf_keys(schema, prefix=""):
    for name, spec in schema.items():
        key = f"{prefix}{name}"
        if isinstance(spec, dict):
            yield from leaf_keys(spec, key + ".")
        else:
            yield key


def write(tmp_path, text, name="case.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


# ----------------------------------------------------------------------------- defaults

def test_empty_mapping_gives_every_key_with_defaults():
    cfg = load_config({})
    assert cfg == DEFAULTS
    for key in leaf_keys(SCHEMA):
        get_path(cfg, key)  # present
    assert cfg.mechanism.preset == "realistic"
    assert cfg.joints.A.socket_radius == 0.015
    assert cfg.solver.baumgarte == (5.0, 5.0)
    assert cfg.wear.map == (144, 288)


def test_defaults_are_the_documented_contract():
    doc = Path(__file__).parents[1] / "docs" / "architecture.md"
    if not doc.exists():
        pytest.skip("docs/architecture.md is not beside the tests")
    block = yaml.safe_load(re.search(r"```yaml\n(.*?)```", doc.read_text(), re.S).group(1))
    block["joints"]["B"] = block["joints"]["A"]  # "same keys for B"
    assert block == DEFAULTS.to_dict()
    assert load_config(block) == DEFAULTS


def test_result_is_frozen_and_inputs_are_untouched():
    source = {"solver": {"dt": 1e-6}}
    before = copy.deepcopy(source)
    cfg = load_config(source)
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.joints.A.clearance = 9.0   # type: ignore[misc]
    assert isinstance(cfg.solver.baumgarte, tuple)   # no list to change in place either
    assert source == before
    assert load_config({}).joints.B.clearance == 0.0
    assert DEFAULTS == Config() and hash(DEFAULTS) == hash(Config())


def test_a_config_is_passed_on_as_it_is_and_changed_only_through_validation():
    cfg = load_config({"joints": {"B": {"clearance": 2.5e-4}}})
    assert load_config(cfg) is cfg                       # validated once, not again
    changed = cfg.replace("joints.B.coating=PTFE", joints__A__clearance=1e-4)
    assert (changed.joints.A.clearance, changed.joints.B.coating) == (1e-4, "PTFE")
    assert cfg.joints.B.coating == "none"
    with pytest.raises(ConfigError, match="joints.A.clearance"):
        cfg.replace(joints__A__clearance=-1.0)
    assert load_config(cfg.to_dict()) == cfg              # the plain dict round-trips


def test_every_leaf_carries_units_and_a_long_name_in_its_metadata():
    def leaves(cls, prefix=""):
        for f in dataclasses.fields(cls):
            if f.default_factory is not dataclasses.MISSING:
                yield from leaves(f.default_factory, f"{prefix}{f.name}.")
            else:
                yield prefix + f.name, f
    keys = dict(leaves(Config))
    assert set(keys) == set(leaf_keys(SCHEMA))
    for key, f in keys.items():
        assert {"units", "long_name", "field"} <= set(f.metadata), key
    assert keys["joints.B.clearance"].metadata["units"] == "m"
    assert keys["mechanism.speed_rpm"].metadata["units"] == "min-1"


def test_numbers_are_normalised(tmp_path):
    path = write(tmp_path, """
joints:
  A: {clearance: 0, socket_radius: 1}
mechanism: {gravity: [0, 0, -10], speed_rpm: 30}
wear: {map: [18, 36]}
solver: {baumgarte: [50, 50], dt: 1e-6, duration: 2}
""")
    cfg = load_config(path)
    assert cfg.joints.A.clearance == 0.0 and type(cfg.joints.A.clearance) is float
    assert type(cfg.joints.A.socket_radius) is float
    assert [type(g) for g in cfg.mechanism.gravity] == [float] * 3
    assert cfg.mechanism.gravity == (0.0, 0.0, -10.0)
    assert [type(v) for v in cfg.wear.map] == [int, int]
    assert [type(v) for v in cfg.solver.baumgarte] == [float, float]
    assert cfg.solver.dt == 1e-6  # written without a dot, still a number
    assert type(cfg.solver.duration) is float and type(cfg.solver.save_every) is int


def test_tuples_become_lists():
    cfg = load_config({"mechanism": {"gravity": (0, 0, 0)}})
    assert cfg.mechanism.gravity == (0.0, 0.0, 0.0)


def test_empty_section_means_defaults(tmp_path):
    assert load_config(write(tmp_path, "wear:\nsolver:\n")) == DEFAULTS


# ----------------------------------------------------------------------------- overrides

@pytest.mark.parametrize("override, key, expected", [
    ("solver.dt=2e-6", "solver.dt", 2e-6),
    ("solver.duration=3", "solver.duration", 3.0),
    ("solver.save_every=5", "solver.save_every", 5),
    ("solver.baumgarte=[50,50]", "solver.baumgarte", [50.0, 50.0]),
    ("wear.map=[10, 20]", "wear.map", [10, 20]),
    ("friction.enabled=false", "friction.enabled", False),
    ("joints.B.coating=PTFE", "joints.B.coating", "PTFE"),
    ("joints.A.wear_coefficient=1.0e-13", "joints.A.wear_coefficient", 1e-13),
    ("joints.A.wear_coefficient=null", "joints.A.wear_coefficient", None),
    ("mechanism.preset=paper", "mechanism.preset", "paper"),
    ("name=my run", "name", "my run"),
    ("joints.B={clearance: 2.5e-4}", "joints.B.clearance", 2.5e-4),
])
def test_override_types(override, key, expected):
    cfg = load_config({}, [override])
    assert get_path(cfg, key) == expected
    assert type(get_path(cfg, key)) is type(expected)


def test_overrides_apply_in_order_over_the_file(tmp_path):
    path = write(tmp_path, "solver: {dt: 1.0e-5}\n")
    cfg = load_config(path, ["solver.dt=1e-6", "solver.dt=3e-6"])
    assert cfg.solver.dt == 3e-6


def test_a_single_string_is_one_override():
    assert load_config({}, "solver.dt=2e-6").solver.dt == 2e-6


def test_apply_override_set_path_get_path():
    cfg = DEFAULTS.to_dict()
    assert apply_override(cfg, "joints.A.clearance=2.5e-4") is cfg
    assert get_path(cfg, "joints.A.clearance") == 2.5e-4
    set_path(cfg, "contact.restitution", 0.5)
    assert cfg["contact"]["restitution"] == 0.5
    new = {}
    set_path(new, "a.b.c", 1)
    assert new == {"a": {"b": {"c": 1}}}


@pytest.mark.parametrize("override", ["solver.dt", "=1", "solver..dt=1", ""])
def test_malformed_override(override):
    with pytest.raises(ConfigError, match="KEY=VALUE"):
        load_config({}, [override])


def test_get_path_unknown_key_suggests():
    with pytest.raises(ConfigError, match=r"did you mean 'solver\.dt'\?") as info:
        get_path(DEFAULTS, "solver.dtt")
    assert info.value.key == "solver.dtt"


def test_set_path_through_a_value_is_an_error():
    with pytest.raises(ConfigError, match="solver.dt is a value"):
        set_path(DEFAULTS.to_dict(), "solver.dt.x", 1)


def test_error_from_override_is_marked(tmp_path):
    path = write(tmp_path, "solver: {dt: 1.0e-5}\n")
    with pytest.raises(ConfigError) as info:
        load_config(path, ["solver.dt=-1"])
    assert str(info.value) == f"{path}: solver.dt: got -1 (from --set); expected a number > 0"


def test_override_value_that_is_bad_yaml():
    with pytest.raises(ConfigError, match=r"solver\.baumgarte: got '\[50,50'; expected valid YAML"):
        load_config({}, ["solver.baumgarte=[50,50"])


# ----------------------------------------------------------------------------- round trips

def test_dump_load_round_trip(tmp_path):
    cfg = load_config({"name": "rt", "joints": {"B": {"clearance": 2.5e-4, "coating": "PTFE"}},
                       "solver": {"dt": 1e-6, "baumgarte": [50, 50]}})
    text = dump_config(cfg)
    assert list(yaml.safe_load(text)) == list(SCHEMA)
    assert load_config(write(tmp_path, text)) == cfg
    assert load_config(cfg) == cfg


def _field_values(spec):
    """Hypothesis strategy for valid values of one schema field."""
    if isinstance(spec.kind, tuple):
        return st.sampled_from(spec.kind)
    if spec.kind is bool:
        return st.booleans()
    if spec.kind is str:
        text = st.text(st.characters(codec="utf-8", exclude_categories=("Cs", "Cc")), max_size=12)
        return st.one_of(st.none(), text) if spec.nullable else text
    if spec.kind is int:
        one = st.integers(min_value=int(spec.lo), max_value=int(spec.hi) if spec.hi is not None else 10**6)
    else:
        lo = spec.lo if spec.lo is not None else -1e6
        hi = spec.hi if spec.hi is not None else 1e6
        one = st.floats(lo, hi, exclude_min=spec.lo_open, exclude_max=spec.hi_open,
                        allow_nan=False, allow_infinity=False)
    if spec.size:
        return st.lists(one, min_size=spec.size, max_size=spec.size)
    return st.one_of(st.none(), one) if spec.nullable else one


def _configs(schema=SCHEMA):
    return st.fixed_dictionaries({name: _configs(spec) if isinstance(spec, dict) else _field_values(spec)
                                  for name, spec in schema.items() if name != "materials_file"})


def _consistent(raw):
    """Make the drawn values satisfy the relations between fields."""
    mechanism = raw["mechanism"]       # a preset of its mechanism
    presets = config_module.MECHANISM_KINDS[mechanism["kind"]]
    if mechanism["preset"] not in presets:
        mechanism["preset"] = presets[0]
    longest = config_module.PRESET_LINKS_M[mechanism["preset"]][1]
    for pin in config_module.PIN_JOINTS:      # a pin's type: its mechanism's, or a bushing
        if raw["joints"][pin]["type"] != "bushing":
            raw["joints"][pin]["type"] = config_module.pin_type(mechanism["kind"])
    for joint in raw["joints"].values():      # sizes bounded against the mechanism
        for key in ("clearance", "clearance_y", "clearance_z"):
            if key in joint and joint[key] < config_module.MIN_CLEARANCE_M:
                joint[key] = 0.0
        if joint["wear_coefficient"] is not None:
            joint["wear_coefficient"] = min(joint["wear_coefficient"], config_module.MAX_WEAR_COEFFICIENT)
        for key in ("length", "base_thickness", "coating_thickness"):
            if joint.get(key) is not None:
                joint[key] = min(joint[key], longest)
                if key != "length" and 0.0 < joint[key] < config_module.MIN_LAYER_M:
                    joint[key] = config_module.MIN_LAYER_M
    if mechanism["kind"] != "slider_crank":     # a pin's bearing length: the slider-crank's
        for name in config_module.SLIDER_CRANK_PINS:
            raw["joints"][name]["length"] = None
    bearing = raw["joints"]["O"]
    crank = config_module.PRESET_LINKS_M[mechanism["preset"]][0]   # room for 3 c below
    bearing["bearing_radius"] = min(max(bearing["bearing_radius"], config_module.MIN_BEARING_RADIUS_M),
                                    0.25 * crank)
    bearing["clearance"] = min(bearing["clearance"], 0.25 * bearing["bearing_radius"])
    bearing["coating_thickness"] = min(bearing["coating_thickness"], 0.5 * bearing["bearing_radius"])
    guide = raw["joints"]["P"]
    if mechanism["kind"] == "slider_crank":
        for pin in ("A", "B"):      # a pin's bushing: its axial values the radial ones
            for key in ("bushing_stiffness", "bushing_damping"):
                raw["joints"][pin][key] = [raw["joints"][pin][key][0]] * 2
    guide["corner_radius"] = min(max(guide["corner_radius"], config_module.MIN_CORNER_RADIUS_M), 0.01)
    guide["block"] = [min(side, longest) for side in guide["block"]]
    if (guide["clearance_y"] > 0.0) != (guide["clearance_z"] > 0.0):   # both or neither
        guide["clearance_z"] = guide["clearance_y"]
    if mechanism["kind"] == "slider_crank":     # its side gap at least its gap in the plane
        guide["clearance_y"] = max(guide["clearance_y"], guide["clearance_z"])
    guide["block"] = [max(side, 2.0 * guide["corner_radius"]) for side in guide["block"]]
    guide["coating"] = guide["coating"] if guide["coating"] in ("none", "PTFE", "lead") else "MoS2"
    if guide["clearance_y"] > 0.0:          # a row at least for each of the guide's four walls
        raw["wear"]["map"] = [max(raw["wear"]["map"][0], 4), raw["wear"]["map"][1]]
    for name, joint in raw["joints"].items():
        if name == "P":
            continue
        # room for the clearance and its tolerance band (at most 1.5 c, below): c + t <= R / 2
        radius = radius_key(joint)
        joint[radius] = 3.0 * joint["clearance"] + joint[radius]
        joint["coating"] = joint["coating"] if joint["coating"] in ("none", "PTFE", "lead") else "MoS2"
        if joint.get("type") == "bushing":   # a bushing has no clearance and no coating
            joint["clearance"] = 0.0
            joint["coating"] = "none"
    raw["friction"]["v1"] = 2.0 * raw["friction"]["v0"] + raw["friction"]["v1"]
    raw["solver"]["duration"] = raw["solver"]["dt"] + raw["solver"]["duration"]
    if raw["solver"]["revolutions"] is not None or raw["metrics"]["settle_revolutions"] is not None:
        # revolutions at a speed that gives them a finite length in seconds (a denormal speed
        # is refused, naming it)
        raw["mechanism"]["speed_rpm"] = max(raw["mechanism"]["speed_rpm"], 1e-3)
    if raw["solver"]["revolutions"] is not None:    # one length of the two; at least dt
        raw["solver"]["duration"] = None
        raw["solver"]["revolutions"] += 2.0 * raw["solver"]["dt"] * raw["mechanism"]["speed_rpm"] / 60.0
    if raw["metrics"]["settle_revolutions"] is not None:
        raw["metrics"]["settle_time"] = None
    # member < members, both inside their bounds
    raw["ensemble"]["member"] = raw["ensemble"]["member"] % raw["ensemble"]["members"]
    if raw["ensemble"]["members"] == 1:     # perturbations need an ensemble
        raw["ensemble"]["perturb"] = {k: 0.0 for k in raw["ensemble"]["perturb"]}
    solver = raw["solver"]      # dopri5's longest step no shorter than its shortest
    if solver["max_step"] is not None:
        solver["max_step"] = max(solver["max_step"], solver["dt"] / 2 ** solver["max_substep_level"])
    rel = raw["reliability"]
    rel["member"] = rel["member"] % rel["members"]
    clearances = [section_clearance(j) for j in raw["joints"].values() if section_clearance(j) > 0.0]
    rel["clearance_tolerance"] = min([rel["clearance_tolerance"], *(0.5 * c for c in clearances)])
    return raw


@settings(max_examples=60, deadline=None)
@given(_configs().map(_consistent))
def test_round_trip_property(raw):
    cfg = load_config(raw)
    assert load_config(yaml.safe_load(dump_config(cfg))) == cfg
    assert dump_config(load_config(yaml.safe_load(dump_config(cfg)))) == dump_config(cfg)


# ----------------------------------------------------------------------------- errors

BAD = [
    # (yaml text, key, value received, words expected in the message)
    ("joints:\n  A:\n    clearence: 0.001\n", "joints.A.clearence", 0.001,
     "did you mean 'joints.A.clearance'?"),
    ("mechanim: {}\n", "mechanim", {}, "did you mean 'mechanism'?"),
    ("joints:\n  B:\n    coating: ptfe\n", "joints.B.coating", "ptfe", "did you mean 'PTFE'?"),
    ("joints:\n  B:\n    coating: teflon\n", "joints.B.coating", "teflon", "a known material"),
    ("joints:\n  A:\n    clearance: -0.001\n", "joints.A.clearance", -0.001, "a number >= 0"),
    ("joints:\n  A:\n    clearance: 0.02\n", "joints.A.clearance", 0.02,
     "<= 0.5 * joints.A.socket_radius (0.0075)"),
    ("joints:\n  B:\n    socket_radius: 1.0e-4\n    clearance: 2.0e-4\n", "joints.B.clearance", 2e-4,
     "<= 0.5 * joints.B.socket_radius"),
    # a ball of 0.1 mm in a 15 mm socket used to run "ok" while penetrating 590 radii deep
    ("joints:\n  B:\n    clearance: 0.0149\n", "joints.B.clearance", 0.0149,
     "the ball radius R_j = socket_radius - clearance is at least 0.5 * socket_radius"),
    ("joints:\n  O:\n    clearance: 0.009\n", "joints.O.clearance", 0.009,
     "the journal radius R_j = bearing_radius - clearance is at least 0.5 * bearing_radius"),
    ("joints:\n  O:\n    length: 0\n", "joints.O.length", 0, "a number > 0"),
    ("joints:\n  O:\n    bearing_radius: -0.01\n", "joints.O.bearing_radius", -0.01, "a number > 0"),
    ("joints:\n  O:\n    socket_radius: 0.01\n", "joints.O.socket_radius", 0.01, "bearing_radius"),
    ("joints:\n  O:\n    coating: teflon\n", "joints.O.coating", "teflon", "a known material"),
    ("solver:\n  dt: 0\n", "solver.dt", 0, "a number > 0"),
    ("solver:\n  dt: -1.0e-5\n", "solver.dt", -1e-5, "a number > 0"),
    ("solver:\n  dt: 2.0\n", "solver.dt", 2.0, "<= solver.duration (1.0)"),
    ("solver:\n  dt: fast\n", "solver.dt", "fast", "a number > 0"),
    ("solver:\n  dt: '1.0e-5'\n", "solver.dt", "1.0e-5", "a number > 0"),
    ("mechanism:\n  speed_rpm: true\n", "mechanism.speed_rpm", True, "a number > 0"),
    ("mechanism:\n  speed_rpm: .nan\n", "mechanism.speed_rpm", float("nan"), "a number > 0"),
    ("mechanism:\n  gravity: [0, -9.81]\n", "mechanism.gravity", [0, -9.81], "a list of 3 numbers"),
    ("mechanism:\n  preset: papr\n", "mechanism.preset", "papr", "did you mean 'paper'?"),
    # the mechanism and its presets (issue 44)
    ("mechanism:\n  kind: four_bar\n", "mechanism.kind", "four_bar", "one of 'rssp', 'slider_crank'"),
    ("mechanism:\n  kind: slidercrank\n", "mechanism.kind", "slidercrank",
     "did you mean 'slider_crank'?"),
    ("mechanism:\n  kind: slider_crank\n", "mechanism.preset", "realistic",
     "a preset of mechanism.kind slider_crank: one of flores_benchmark"),
    ("mechanism:\n  preset: flores_benchmark\n", "mechanism.preset", "flores_benchmark",
     "a preset of mechanism.kind rssp: one of realistic, paper"),
    ("mechanism: {kind: slider_crank, preset: flores_benchmark}\n"
     "joints: {P: {clearance_y: 5.0e-5, clearance_z: 1.0e-4}}\n", "joints.P.clearance_y", 5e-5,
     ">= joints.P.clearance_z (0.0001 m) where mechanism.kind is slider_crank"),
    ("contact:\n  restitution: 0\n", "contact.restitution", 0, "0 < x <= 1"),
    ("contact:\n  restitution: 1.5\n", "contact.restitution", 1.5, "0 < x <= 1"),
    ("contact:\n  layer_rule: paper\n", "contact.layer_rule", "paper", "'series', 'paper_mm'"),
    ("friction:\n  v0: 1.0e-3\n  v1: 1.0e-4\n", "friction.v1", 1e-4, "> friction.v0"),
    ("friction:\n  enabled: 1\n", "friction.enabled", 1, "true or false"),
    ("wear:\n  slip: slide\n", "wear.slip", "slide", "did you mean 'sliding'?"),
    ("wear:\n  map: [0, 72]\n", "wear.map", [0, 72], "a list of 2 integers >= 1"),
    ("wear:\n  map: [36.0, 72]\n", "wear.map", [36.0, 72], "integers"),
    ("wear:\n  amplification: -1\n", "wear.amplification", -1, ">= 0"),
    ("solver:\n  save_every: 0\n", "solver.save_every", 0, "an integer >= 1"),
    ("solver:\n  save_every: 2.5\n", "solver.save_every", 2.5, "an integer >= 1"),
    ("solver:\n  max_substep_level: 17\n", "solver.max_substep_level", 17, "0 <= x <= 16"),
    ("solver:\n  stability_limit: 2.8\n", "solver.stability_limit", 2.8, "0 < x < 2.8"),
    ("solver:\n  baumgarte: [5, -1]\n", "solver.baumgarte", [5, -1], "2 numbers >= 0"),
    ("solver: 5\n", "solver", 5, "a mapping with keys dt, duration"),
    ("name: 12\n", "name", 12, "a string"),
    # a sweep key beside case keys (a sweep file alone: tests/test_file_kinds.py)
    ("mechanism: {}\nsweep:\n  grid: {}\n", "sweep", {"grid": {}}, "clearsweep sweep"),
    ("joints: {}\nbase: {}\n", "base", {}, "clearsweep sweep"),
]


@pytest.mark.parametrize("text, key, value, words", BAD, ids=[b[1] + ":" + repr(b[2]) for b in BAD])
def test_bad_values_name_file_key_and_value(tmp_path, text, key, value, words):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    err = info.value
    assert err.key == key and err.source == str(path)
    assert str(err).startswith(f"{path}: {key}: got {value!r}; expected ")
    assert words in str(err)


def test_message_format_exactly():
    with pytest.raises(ConfigError) as info:
        load_config({"joints": {"A": {"clearence": 0.001}}}, source_name="my.yaml")
    assert str(info.value) == (
        "my.yaml: joints.A.clearence: got 0.001; expected one of the keys of joints.A (clearance, "
        "socket_radius, coating, coating_thickness, base_thickness, wear_coefficient, type, "
        "bushing_stiffness, bushing_damping, length); "
        "did you mean 'joints.A.clearance'?")
    assert info.value.value == 0.001 and info.value.suggestion == "joints.A.clearance"
    assert isinstance(info.value, ValueError)


def test_dict_source_is_named_config():
    with pytest.raises(ConfigError, match=r"^<config>: solver\.dt: got -1;"):
        load_config({"solver": {"dt": -1}})


def test_malformed_yaml_names_file_and_line(tmp_path):
    path = write(tmp_path, "name: x\nsolver:\n  dt: [1.0e-5\n  duration: 1\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value).startswith(f"{path}: line ")
    assert info.value.line in (3, 4) and "expected valid YAML" in str(info.value)


@pytest.mark.parametrize("text, got", [("", "an empty file"), ("# only a comment\n", "an empty file"),
                                       ("- a\n- b\n", "['a', 'b']"), ("just text\n", "'just text'")])
def test_top_level_must_be_a_mapping(tmp_path, text, got):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match="expected a mapping with keys name, materials_file") as info:
        load_config(path)
    assert str(info.value).startswith(f"{path}: got {got}; ")


def test_missing_file():
    with pytest.raises(ConfigError, match=r"no/such\.yaml: got 'no/such\.yaml' \(No such file"):
        load_config("no/such.yaml")


def test_errors_survive_pickling():
    with pytest.raises(ConfigError) as info:
        load_config({"joints": {"B": {"coating": "ptfe"}}}, source_name="c.yaml")
    again = pickle.loads(pickle.dumps(info.value))
    assert str(again) == str(info.value) and again.key == "joints.B.coating"


# ----------------------------------------------------------------------------- materials file

USER_MATERIALS = """
bronze:
  youngs_modulus_Pa: {value: 1.1e+11, source: "handbook"}
  poisson_ratio: {value: 0.34, source: "handbook"}
  friction_coefficient: {value: 0.1, source: "handbook"}
  wear_coefficient_m2_per_N: {value: 1.0e-13, source: "handbook"}
"""


def test_materials_file_is_relative_to_the_config(tmp_path, monkeypatch):
    (tmp_path / "cfg").mkdir()
    write(tmp_path / "cfg", USER_MATERIALS, "mine.yaml")
    path = write(tmp_path / "cfg", "materials_file: mine.yaml\njoints: {B: {coating: bronze}}\n")
    monkeypatch.chdir(tmp_path)
    cfg = load_config("cfg/case.yaml")
    assert cfg.materials_file == str(tmp_path / "cfg" / "mine.yaml")
    assert resolve_materials(cfg)["bronze"].friction_coefficient == 0.1
    assert load_config(write(tmp_path, dump_config(cfg), "elsewhere.yaml")) == cfg
    assert load_config(path, ["joints.A.coating=bronze"]).joints.A.coating == "bronze"


def test_missing_materials_file(tmp_path):
    path = write(tmp_path, "materials_file: nope.yaml\n")
    with pytest.raises(ConfigError, match=r"materials_file: got 'nope\.yaml'; expected an existing"):
        load_config(path)


def test_user_material_unknown_without_its_file():
    with pytest.raises(ConfigError, match="joints.B.coating: got 'bronze'"):
        load_config({"joints": {"B": {"coating": "bronze"}}})


# ----------------------------------------------------------------------------- hostile YAML

def alias_bomb(levels: int = 9) -> str:
    """A "billion laughs" document: a few hundred bytes that stand for 9**levels strings."""
    text = "a0: &a0 [" + ", ".join(["lol"] * 9) + "]\n"
    for i in range(1, levels):
        text += f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]\n"
    return text


def test_alias_bomb_is_refused_before_it_expands(tmp_path):
    path = write(tmp_path, alias_bomb())
    assert path.stat().st_size < 1024
    with pytest.raises(ConfigError, match="values once its aliases are expanded") as info:
        parse_yaml(path.read_text(), str(path))
    assert str(info.value).startswith(f"{path}: line ")
    with pytest.raises(ConfigError, match="values once its aliases are expanded"):
        load_config(path)


def test_a_few_aliases_are_still_fine():
    assert parse_yaml("a: &x [1, 2]\nb: *x\n") == {"a": [1, 2], "b": [1, 2]}


def test_too_many_aliases_are_refused():
    text = "a: &x 1\nb: [" + ", ".join(["*x"] * (MAX_YAML_ALIASES + 1)) + "]\n"
    with pytest.raises(ConfigError, match=f"more than {MAX_YAML_ALIASES} aliases"):
        parse_yaml(text)


@pytest.mark.parametrize("text", ["x: " + "[" * 20000 + "]" * 20000 + "\n",
                                  "".join("  " * i + f"k{i}:\n" for i in range(200))],
                         ids=["flow", "block"])
def test_deep_nesting_is_a_config_error(tmp_path, text):
    path = write(tmp_path, text)
    with pytest.raises(ConfigError, match="levels of nesting") as info:
        load_config(path)
    assert str(info.value).startswith(f"{path}: line ")


def test_oversized_file_is_refused_unread(tmp_path):
    path = write(tmp_path, "name: x\n" + "# padding\n" * (MAX_YAML_BYTES // 10 + 1))
    with pytest.raises(ConfigError, match=f"at most {MAX_YAML_BYTES} bytes"):
        load_config(path)


def test_duplicate_key_names_the_key_and_both_lines(tmp_path):
    path = write(tmp_path, "solver:\n  dt: 1.0e-5\n  duration: 0.1\n  dt: 2.0e-5\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == (f"{path}: line 4: got the key 'dt' a second time (first on line 2); "
                               "expected each key once in a mapping")


def test_same_key_in_different_mappings_is_fine():
    assert load_config({}).joints.A.clearance == 0.0
    assert parse_yaml("A: {clearance: 1}\nB: {clearance: 2}\n") == {"A": {"clearance": 1},
                                                                      "B": {"clearance": 2}}


# ------------------------------------------------ lengths in crank revolutions (issue 41)

@pytest.mark.parametrize("section, seconds, revolutions", [
    ("solver", "duration", "revolutions"), ("metrics", "settle_time", "settle_revolutions")])
def test_a_length_in_seconds_and_in_revolutions_both_is_refused_naming_both(
        tmp_path, section, seconds, revolutions):
    path = write(tmp_path, f"{section}: {{{seconds}: 0.5, {revolutions}: 1}}\n")
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert err.value.key == f"{section}.{revolutions}"
    assert f"{section}.{seconds}" in str(err.value) and "not both" in str(err.value)
    assert "\n" not in str(err.value)


def test_neither_length_gives_the_defaults_in_seconds():
    cfg = load_config({})
    assert (cfg.solver.duration, cfg.solver.revolutions) == (1.0, None)
    assert (cfg.metrics.settle_time, cfg.metrics.settle_revolutions) == (0.05, None)
    # null for the seconds key is "not given", as a resolved config's dict writes it
    assert load_config({"solver": {"duration": None}}).solver.duration == 1.0


def test_revolutions_resolve_to_seconds_at_the_cases_speed():
    cfg = load_config({"mechanism": {"speed_rpm": 120.0}, "solver": {"revolutions": 3},
                       "metrics": {"settle_revolutions": 1}})
    assert cfg.solver.duration == 3 * 60.0 / 120.0 and cfg.solver.revolutions == 3.0
    assert cfg.metrics.settle_time == 60.0 / 120.0 and cfg.metrics.settle_revolutions == 1.0
    # what was asked is what the dict (the results' config text) holds: at another speed
    # the same revolutions, resolved again
    assert cfg.to_dict()["solver"]["duration"] is None
    slower = cfg.replace(mechanism__speed_rpm=40.0)
    assert (slower.solver.duration, slower.metrics.settle_time) == (4.5, 1.5)
    assert load_config(yaml.safe_load(dump_config(cfg))) == cfg


def test_a_later_setting_of_one_unit_replaces_the_others_length(tmp_path):
    path = write(tmp_path, "solver: {duration: 2.0}\nmetrics: {settle_revolutions: 2}\n")
    cfg = load_config(path, ["solver.revolutions=5", "metrics.settle_time=0.25"])
    assert (cfg.solver.duration, cfg.solver.revolutions) == (5.0, 5.0)
    assert (cfg.metrics.settle_time, cfg.metrics.settle_revolutions) == (0.25, None)
    # a block of a life run sets its duration over a config asked in revolutions
    assert cfg.replace(solver__duration=0.5).solver.revolutions is None
    with pytest.raises(ConfigError, match=r"solver.duration: got 1 \(from --set\); expected one "
                                          r"of solver.revolutions and solver.duration, not both"):
        load_config(path, ["solver.revolutions=5", "solver.duration=1"])


# ----------------------------------------------------------------------------- mechanisms

def test_the_mechanisms_presets_are_the_params_presets():
    """config.MECHANISM_KINDS names each mechanism's presets, params.PRESETS holds their
    data: the same presets, each of the mechanism that lists it (its guide along x for the
    RSSP, along y for the slider-crank), and each mechanism's first preset valid with it."""
    from clearsweep.params import PRESETS

    assert set(config_module.PRESET_KINDS) == set(PRESETS)
    for name, preset in PRESETS.items():
        assert preset.kind == config_module.PRESET_KINDS[name], name
        assert preset.guide_axis == (1 if preset.kind == "slider_crank" else 0)
    assert DEFAULTS.mechanism.kind == "rssp" and DEFAULTS.mechanism.preset == "realistic"
    for kind, presets in config_module.MECHANISM_KINDS.items():
        cfg = load_config({"mechanism": {"kind": kind, "preset": presets[0]}})
        assert (cfg.mechanism.kind, cfg.mechanism.preset) == (kind, presets[0])
