"""Materials: shipped values (docs/physics.md section 6) with sources, user files, error messages."""

import dataclasses

import pytest

from clearsweep.config import ConfigError
from clearsweep.materials import FIELDS, Material, format_materials, load_materials

# docs/physics.md section 6 (Jing & Liu 2023, Table 3): E [Pa], nu, mu, k [m^2/N], k assumed
TABLE_3 = {
    "steel": (207e9, 0.30, 0.01, 8e-14, False),
    "MoS2": (110e9, 0.29, 0.05, 8e-14, True),
    "lead": (16.5e9, 0.42, 0.08, 8e-14, True),
    "PTFE": (2.86e9, 0.40, 0.167, 8e-14, True),
}


def values(m: Material):
    return (m.youngs_modulus_Pa, m.poisson_ratio, m.friction_coefficient, m.wear_coefficient_m2_per_N,
            m.wear_coefficient_assumed)


def test_shipped_values_match_design_table():
    materials = load_materials()
    assert list(materials) == list(TABLE_3)
    for name, expected in TABLE_3.items():
        assert materials[name].name == name
        assert values(materials[name]) == pytest.approx(expected, rel=1e-12)


def test_every_value_has_a_source():
    for m in load_materials().values():
        assert set(m.sources) == set(FIELDS)
        assert all(isinstance(s, str) and s.strip() for s in m.sources.values())
        assert "Jing & Liu 2023" in m.sources["youngs_modulus_Pa"]


def test_coating_wear_coefficients_are_flagged_assumed():
    materials = load_materials()
    assert not materials["steel"].wear_coefficient_assumed
    for name in ("MoS2", "lead", "PTFE"):
        assert materials[name].wear_coefficient_assumed
        assert materials[name].wear_coefficient_m2_per_N == materials["steel"].wear_coefficient_m2_per_N
        assert "assumed" in materials[name].sources["wear_coefficient_m2_per_N"]


def test_material_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        load_materials()["steel"].poisson_ratio = 0.2


def test_unknown_name_suggests_the_case_sensitive_one():
    materials = load_materials()
    with pytest.raises(KeyError, match=r"did you mean 'PTFE'\?"):
        materials["ptfe"]
    with pytest.raises(ConfigError, match=r"did you mean 'MoS2'\?"):
        materials["MoS3"]
    assert "ptfe" not in materials and materials.get("ptfe") is None


def test_user_file_adds_and_overrides(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("""
PTFE:
  wear_coefficient_m2_per_N: {value: 2.0e-13, source: "pin-on-disc, lab report 7"}
bronze:
  youngs_modulus_Pa: {value: 1.1e+11, source: "handbook p. 3"}
  poisson_ratio: {value: 0.34, source: "handbook p. 3"}
  friction_coefficient: {value: 0.1, source: "handbook p. 4"}
  wear_coefficient_m2_per_N: {value: 1.0e-13, assumed: true, source: "guess"}
""")
    materials = load_materials(path)
    assert list(materials) == [*TABLE_3, "bronze"]
    ptfe = materials["PTFE"]
    assert ptfe.wear_coefficient_m2_per_N == 2e-13 and not ptfe.wear_coefficient_assumed
    assert ptfe.sources["wear_coefficient_m2_per_N"] == "pin-on-disc, lab report 7"
    assert ptfe.youngs_modulus_Pa == 2.86e9 and "Table 3" in ptfe.sources["youngs_modulus_Pa"]
    assert values(materials["bronze"]) == (1.1e11, 0.34, 0.1, 1e-13, True)
    assert load_materials()["PTFE"].wear_coefficient_m2_per_N == 8e-14  # shipped data unchanged


BAD_FILES = [
    # (file text, key named, value received, words expected)
    ("PTFE:\n  friction_coefficient: {value: high, source: x}\n", "PTFE.friction_coefficient.value",
     "high", "a number with 0 <= x <= 2"),
    ("PTFE:\n  friction_coefficient: {value: 0.2}\n", "PTFE.friction_coefficient.source", None,
     "a non-empty text"),
    ("PTFE:\n  friction_coefficient: 0.2\n", "PTFE.friction_coefficient", 0.2, "a mapping {value"),
    ("PTFE:\n  friction_coeficient: {value: 0.2, source: x}\n", "PTFE.friction_coeficient",
     {"value": 0.2, "source": "x"}, "did you mean 'friction_coefficient'?"),
    ("PTFE:\n  poisson_ratio: {value: 0.5, source: x}\n", "PTFE.poisson_ratio.value", 0.5, "-1 < x < 0.5"),
    ("PTFE:\n  youngs_modulus_Pa: {value: -1, source: x}\n", "PTFE.youngs_modulus_Pa.value", -1, "> 0"),
    ("PTFE:\n  poisson_ratio: {value: 0.3, source: x, assumed: true}\n", "PTFE.poisson_ratio.assumed",
     True, "only the keys {value: ..., source: ...}"),
    ("PTFE:\n  wear_coefficient_m2_per_N: {value: 1.0e-13, source: x, assumed: maybe}\n",
     "PTFE.wear_coefficient_m2_per_N.assumed", "maybe", "true or false"),
    ("bronze:\n  poisson_ratio: {value: 0.3, source: x}\n", "bronze.youngs_modulus_Pa", None,
     "missing: youngs_modulus_Pa, friction_coefficient, wear_coefficient_m2_per_N"),
    ("bronze: 3\n", "bronze", 3, "a mapping with the fields"),
]


@pytest.mark.parametrize("text, key, value, words", BAD_FILES, ids=[b[1] for b in BAD_FILES])
def test_bad_user_file_names_file_material_and_field(tmp_path, text, key, value, words):
    path = tmp_path / "mine.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_materials(path)
    err = info.value
    assert err.source == str(path) and err.key == key and err.value == value
    assert str(err).startswith(f"{path}: {key}: got ")
    assert words in str(err)


@pytest.mark.parametrize("text, words", [("", "got an empty file"), ("- a\n", "got ['a']"),
                                         ("PTFE: {a: [\n", "line 1"), ("none: {}\n", "other than 'none'")])
def test_bad_user_file_as_a_whole(tmp_path, text, words):
    path = tmp_path / "mine.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=rf"^{path}") as info:
        load_materials(path)
    assert words in str(info.value)


def test_missing_user_file(tmp_path):
    with pytest.raises(ConfigError, match="No such file"):
        load_materials(tmp_path / "nope.yaml")


def test_format_lists_values_and_sources():
    text = format_materials(load_materials())
    assert "PTFE" in text and "2.86" in text and "8e-14 (assumed)" in text
    assert "steel.wear_coefficient_m2_per_N: Jing & Liu 2023" in text
    assert text.count("\n  ") == len(TABLE_3) * len(FIELDS)


def test_materials_file_is_read_with_the_yaml_limits(tmp_path):
    user = tmp_path / "m.yaml"
    user.write_text("lead:\n  friction_coefficient: {value: 0.2, source: lab}\n"
                    "lead:\n  friction_coefficient: {value: 0.3, source: lab}\n")
    with pytest.raises(ConfigError, match=r"line 3: got the key 'lead' a second time \(first on line 1\)"):
        load_materials(user)
    user.write_text("x: " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ConfigError, match="levels of nesting"):
        load_materials(user)
