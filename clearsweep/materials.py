"""Joint materials (docs/physics.md section 6): the shipped data file and user files.

``data/materials.yaml`` holds the steel base and the coatings of the paper's
Table 3, every value with its source. A user file has the same format::

    PTFE:                       # override some fields of a shipped material
      wear_coefficient_m2_per_N: {value: 2.0e-13, source: "my pin-on-disc test"}
    bronze:                     # or add a material (all four fields)
      youngs_modulus_Pa: {value: 110.0e+9, source: "..."}
      ...

A wear coefficient with no published value carries ``assumed: true``.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass
from importlib.resources import files
from typing import Any

from .schema import ConfigError, Field, close_match, read_yaml

__all__ = ["Material", "Materials", "UnknownMaterialError", "FIELDS", "load_materials",
           "format_materials"]

#: The largest values a material admits: a friction coefficient of clean metals in air
#: reaches about 1, and 2 is beyond any measured dry pairing (mu = 1e300 overflowed the
#: seated start); the Archard bound of the joints' ``wear_coefficient``
#: (config.MAX_WEAR_COEFFICIENT: k / H of the dirtiest dry wear on the softest coating is
#: about 1e-10 m^2/N).
MAX_FRICTION = 2.0
MAX_WEAR = 1.0e-9

#: Fields of a material, their units and the values they admit.
FIELDS: dict[str, Field] = {
    "youngs_modulus_Pa": Field(None, lo=0.0, lo_open=True),                        # E [Pa]
    "poisson_ratio": Field(None, lo=-1.0, lo_open=True, hi=0.5, hi_open=True),     # nu [-]
    "friction_coefficient": Field(None, lo=0.0, hi=MAX_FRICTION),                  # mu [-]
    "wear_coefficient_m2_per_N": Field(None, lo=0.0, hi=MAX_WEAR),                 # k [m^2/N]
}
_WEAR = "wear_coefficient_m2_per_N"
_SHIPPED = "clearsweep/data/materials.yaml"


@dataclass(frozen=True)
class Material:
    """Elastic, friction and wear data of one joint material.

    Attributes
    ----------
    name : str
        Name as written in the data file (case-sensitive).
    youngs_modulus_Pa : float
        Young's modulus E [Pa].
    poisson_ratio : float
        Poisson's ratio nu [-].
    friction_coefficient : float
        Coulomb friction coefficient mu [-] of this surface against the steel ball.
    wear_coefficient_m2_per_N : float
        Archard wear coefficient k [m^2/N].
    wear_coefficient_assumed : bool
        True where k is not published and a stated default is used.
    sources : dict[str, str]
        Source of each value, keyed by field name.
    """

    name: str
    youngs_modulus_Pa: float
    poisson_ratio: float
    friction_coefficient: float
    wear_coefficient_m2_per_N: float
    wear_coefficient_assumed: bool
    sources: dict[str, str]


class UnknownMaterialError(ConfigError, KeyError):
    """A material name that is not in the table (with the closest known name)."""


class Materials(dict):
    """``name -> Material``; looking up an unknown name suggests the closest known one."""

    def __missing__(self, name: str) -> Material:
        raise UnknownMaterialError(None, name, f"a known material ({', '.join(self)})", "materials",
                                   close_match(name, self))


def _entries(material: Material) -> dict[str, dict[str, Any]]:
    """A material back in data-file form (``field -> {value, source[, assumed]}``)."""
    out = {f: {"value": getattr(material, f), "source": material.sources[f]} for f in FIELDS}
    out[_WEAR]["assumed"] = material.wear_coefficient_assumed
    return out


def _parse_entry(entry: Any, key: str, field: str, source: str) -> dict[str, Any]:
    allowed = ("value", "source", "assumed") if field == _WEAR else ("value", "source")
    form = "{" + ", ".join(f"{a}: ..." for a in allowed) + "}"
    if not isinstance(entry, dict):
        raise ConfigError(key, entry, f"a mapping {form}", source)
    for name in entry:
        if name not in allowed:
            raise ConfigError(f"{key}.{name}", entry[name], f"only the keys {form}", source,
                              close_match(name, allowed))
    text = entry.get("source")
    if not isinstance(text, str) or not text.strip():
        raise ConfigError(f"{key}.source", text, "a non-empty text saying where the value comes from",
                          source)
    return {"value": FIELDS[field].check(entry.get("value"), f"{key}.value", source),
            "source": text.strip(),
            "assumed": Field(False, bool).check(entry.get("assumed", False), f"{key}.assumed", source)}


def _merge(table: Materials, data: Any, source: str) -> Materials:
    """``table`` updated with the materials of one parsed data file."""
    if not isinstance(data, dict) or not data:
        raise ConfigError(None, data, "a mapping of material names to their fields "
                          f"({', '.join(FIELDS)})", source, got="an empty file" if data is None else None)
    out = Materials(table)
    for name, fields in data.items():
        if not isinstance(name, str) or not name.strip() or name == "none":
            raise ConfigError(None, name, "a material name (a non-empty text other than 'none')", source)
        if not isinstance(fields, dict):
            raise ConfigError(name, fields, f"a mapping with the fields {', '.join(FIELDS)}", source)
        entries = _entries(table[name]) if name in table else {}
        for field, entry in fields.items():
            if field not in FIELDS:
                raise ConfigError(f"{name}.{field}", entry, f"one of the fields {', '.join(FIELDS)}",
                                  source, close_match(field, FIELDS))
            entries[field] = _parse_entry(entry, f"{name}.{field}", field, source)
        missing = [f for f in FIELDS if f not in entries]
        if missing:
            raise ConfigError(f"{name}.{missing[0]}", None, f"a value for every field of a new material "
                              f"(missing: {', '.join(missing)})", source, got="nothing")
        # the dataclass fields follow FIELDS in order; mypy cannot count a starred generator
        out[name] = Material(name, *(entries[f]["value"] for f in FIELDS),  # type: ignore[call-arg]
                             entries[_WEAR]["assumed"],
                             {f: entries[f]["source"] for f in FIELDS})
    return out


def load_materials(extra_file: str | os.PathLike | None = None) -> Materials:
    """The shipped materials, merged with a user file.

    Parameters
    ----------
    extra_file
        Optional YAML file in the shipped format; it may add materials (all
        fields given) or override fields of shipped ones.

    Returns
    -------
    Materials
        ``dict[str, Material]`` in file order; an unknown name looked up in it
        raises :class:`UnknownMaterialError` with the closest known name.

    Raises
    ------
    ConfigError
        Naming the file, the material and the field of any bad value.
    """
    if extra_file is None:
        return _load(None, None)
    try:
        stat = os.stat(extra_file)
        stamp = (stat.st_mtime_ns, stat.st_size)
    except OSError:
        stamp = None        # read_yaml says what is wrong with the file
    return _load(str(extra_file), stamp)


@functools.lru_cache(maxsize=16)
def _load(extra_file: str | None, stamp: tuple[int, int] | None) -> Materials:
    # Read once per process and file version (a sweep validates every case against the
    # same files); callers do not change the table they get.
    table = _merge(Materials(), read_yaml(files("clearsweep").joinpath("data").joinpath("materials.yaml"),
                                          _SHIPPED), _SHIPPED)
    if extra_file is not None:
        table = _merge(table, read_yaml(extra_file), extra_file)
    return table


def format_materials(materials: dict[str, Material]) -> str:
    """A text table of ``materials`` and the sources of every value."""
    rows = [("material", "E [GPa]", "nu [-]", "mu [-]", "k [m^2/N]")]
    for m in materials.values():
        rows.append((m.name, f"{m.youngs_modulus_Pa / 1e9:g}", f"{m.poisson_ratio:g}",
                     f"{m.friction_coefficient:g}",
                     f"{m.wear_coefficient_m2_per_N:g}" + (" (assumed)" if m.wear_coefficient_assumed else "")))
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    lines += ["", "sources:"]
    for m in materials.values():
        lines += [f"  {m.name}.{field}: {text}" for field, text in m.sources.items()]
    return "\n".join(lines)
