"""Cases and selections of a results dataset: its sweep dimensions, the cases over them and
their labels, ``--select`` / ``--reference`` parsed against its coordinates, and each
joint's clearance (an ideal joint has none)."""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

import numpy as np
import xarray as xr

from ..ensemble import MEMBER_DIM
from ..jointtypes import elastic
from ..outputs import CASE_DIMS, has_member_statistics, kind_of
from ..outputs import RESULTS_KINDS as _RESULTS_KINDS
from ..schema import close_matches

_MISSING_TEXT = "n/a"


class SelectionError(ValueError):
    """A sweep dimension, coordinate value or metric name that the dataset does not have.

    Attributes
    ----------
    name, value : str
        What was asked for.
    choices : list of str
        What the dataset offers.
    """

    def __init__(self, message: str, *, name: str = "", value: str = "", choices: Iterable = ()):
        super().__init__(message)
        self.name = name
        self.value = value
        self.choices = [str(c) for c in choices]


# --------------------------------------------------------------------------- cases and selections

def sweep_dims(obj: xr.Dataset | xr.DataArray) -> tuple[str, ...]:
    """The sweep dimensions of ``obj``: every dimension that is not a case dimension.

    Ordered as they first appear in the data variables (a dataset's own
    ``dims`` follow its coordinates, not its variables).
    """
    if isinstance(obj, xr.Dataset):
        ordered = dict.fromkeys(d for v in obj.data_vars.values() for d in v.dims)
        ordered.update(dict.fromkeys(obj.dims))
    else:
        ordered = dict.fromkeys(obj.dims)
    return tuple(str(d) for d in ordered if d not in CASE_DIMS)


def value_text(value) -> str:
    """Short text of a coordinate value (``0.00025``, ``PTFE``)."""
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, (float, np.floating)):
        return f"{float(value):g}"
    if isinstance(value, np.generic):
        return str(value.item())
    return str(value)


def label_text(label: Mapping[str, object]) -> str:
    """``"B_coating=PTFE, B_clearance=0.00025"`` from a case label."""
    return ", ".join(f"{k}={value_text(v)}" for k, v in label.items())


#: The unit a figure and a report write a quantity in wherever they give a value of a swept or
#: selected coordinate (the legend of a case, the ``--select`` line of the title, an axis over the
#: coordinate): one unit per quantity, whatever its values, so that a clearance reads in mm
#: on every figure (before: 0.00025 in a legend, 0.00025 m in the title, 250 um on a heat
#: map's axis, 0.25 mm in the orbit's legend; a dynamics map's periodic windows in m and
#: min-1 in ``report``). ``--select`` takes values in these units too
#: (``analysis.parse_selection``). A coordinate of another quantity is written in its units.
QUANTITY_UNITS = {"length": (1e-3, "mm"), "layer thickness": (1e-6, "\u00b5m"),
                  "speed": (1.0, "r/min")}


def quantity_of(coord: xr.DataArray) -> str | None:
    """The quantity of :data:`QUANTITY_UNITS` a coordinate holds, from its units and name: a
    speed (``min-1``, or a ``speed_rpm`` without units), a coating's or base's thickness, any
    other length (clearances, sizes); None for another."""
    unit = str(coord.attrs.get("units", ""))
    name = f"{coord.name} {coord.attrs.get('config_key', '')}"
    if unit == "min-1" or (unit in ("", "1") and str(coord.name).endswith("speed_rpm")):
        return "speed"
    if unit == "m":
        return "layer thickness" if "thickness" in name else "length"
    return None


def quantity_unit(coord: xr.DataArray) -> tuple[float, str]:
    """(factor from the coordinate's SI units, unit text) of a coordinate: its quantity's
    (:func:`quantity_of`), else its own units ("" where it has none)."""
    quantity = quantity_of(coord)
    if quantity is not None:
        return QUANTITY_UNITS[quantity]
    unit = str(coord.attrs.get("units", ""))
    return 1.0, "" if unit in ("", "1") else unit


def quantity_text(coord: xr.DataArray, value) -> str:
    """``"0.25 mm"``, ``"60 r/min"``, ``"PTFE"``: a value of ``coord`` in its quantity's unit
    (:func:`quantity_unit`).

    >>> quantity_text(xr.DataArray([2.5e-4], dims="B_clearance", name="B_clearance",
    ...                             attrs={"units": "m"}), 2.5e-4)
    '0.25 mm'
    """
    factor, unit = quantity_unit(coord)
    if isinstance(value, np.ndarray) and value.ndim == 0:     # a scalar coordinate's values
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.number)):
        return value_text(value)
    number = value_text(float(value) / factor) if factor != 1.0 else value_text(value)
    return f"{number} {unit}" if unit else number


def iter_points(obj: xr.Dataset | xr.DataArray, dims: tuple[str, ...]) -> Iterator[tuple[dict, Any]]:
    """Yield ``({dim: value}, obj at that point)`` over ``dims``.

    The value is the dimension's coordinate value, or the position along a
    dimension without a coordinate.
    """
    for index in itertools.product(*(range(obj.sizes[d]) for d in dims)):
        point = obj.isel(dict(zip(dims, index)))
        yield {d: point[d].values[()] if d in obj.coords else i for d, i in zip(dims, index)}, point


def iter_cases(obj: xr.Dataset | xr.DataArray) -> Iterator[tuple[dict[str, object], Any]]:
    """Yield ``(label, case)`` for every combination of the sweep dimensions.

    ``label`` maps each sweep dimension to the case's coordinate value (its
    position where the dimension has no coordinate), in dimension order, then
    every other coordinate that lives on sweep dimensions only (the keys of a
    zip group, the levels of a stacked case index). A one-case dataset yields
    itself once with an empty label.
    """
    dims = sweep_dims(obj)
    extra = [str(n) for n, c in obj.coords.items()
             if n not in dims and c.dims and set(c.dims) <= set(dims)]
    for label, case in iter_points(obj, dims):
        yield {**label, **{n: case[n].values[()] for n in extra}}, case


#: The longest list of choices an error line prints in full [characters].
MAX_OFFER_CHARS = 300


def choice_message(kind: str, wanted: str, choices: list[str]) -> str:
    """``unknown KIND 'x' (did you mean ...?); choose from: ...``"""
    close = close_matches(wanted, choices, n=3)
    hint = f" (did you mean {', '.join(close)}?)" if close else ""
    offer = ", ".join(choices) if choices else "none"
    if len(offer) > MAX_OFFER_CHARS:    # a line to read, not a dump: the first names and a count
        shown: list[str] = []
        for choice in choices:
            if len(", ".join([*shown, choice])) > MAX_OFFER_CHARS:
                break
            shown.append(choice)
        offer = f"{', '.join(shown)} and {len(choices) - len(shown)} more"
    return f"unknown {kind} {wanted!r}{hint}; choose from: {offer}"


#: The units a ``--select`` value may carry, by its coordinate's SI ``units``: each unit's
#: factor to the coordinate's. The figures write a clearance in mm and a speed in r/min
#: (:data:`QUANTITY_UNITS`): ``B_clearance=0.25mm`` and ``speed_rpm=60rpm`` name
#: the values they show.
SELECT_UNITS = {"m": {"m": 1.0, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "nm": 1e-9},
                "min-1": {"r/min": 1.0, "rpm": 1.0, "min-1": 1.0, "1/min": 1.0}}

_NUMBER_AND_UNIT = re.compile(r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([^\d\s].*?)\s*")


def coordinate_units(coord: xr.DataArray) -> str:
    """The SI units of a coordinate's values (``units``; a swept ``speed_rpm`` without them is
    in ``min-1``); "" where it has none."""
    unit = str(coord.attrs.get("units", ""))
    if unit in ("", "1") and str(coord.name).endswith("speed_rpm"):
        return "min-1"
    return "" if unit == "1" else unit


def _number_in_units(coord: xr.DataArray, name: str, text: str) -> float | None:
    """The number ``text`` gives in the units of ``coord``: a plain number, or a number with
    a unit of :data:`SELECT_UNITS` (``0.25mm``, ``60 rpm``); None where ``text`` is not a
    number.

    Raises
    ------
    SelectionError
        A number with a unit that is not one of the coordinate's quantity.
    """
    try:
        return float(text)
    except ValueError:
        pass
    match = _NUMBER_AND_UNIT.fullmatch(text)
    if match is None or coord.dtype.kind not in "fiu":
        return None
    number, unit = float(match.group(1)), match.group(2)
    units = coordinate_units(coord)
    accepted = SELECT_UNITS.get(units, {units: 1.0} if units else {})
    if unit not in accepted:
        offer = (f"its values are in {units}: give a number in {units}, or one of "
                 f"{', '.join(accepted)}" if accepted else "its values have no unit: give a number")
        raise SelectionError(f"unknown unit {unit!r} in {name}={text} ({offer})",
                             name=name, value=text, choices=list(accepted))
    return number * accepted[unit]


def _match_value(coord: xr.DataArray, name: str, wanted) -> object:
    """The value of ``coord`` that ``wanted`` (text or value) names: exact text or equal
    number, a number given with a unit of its quantity (:data:`SELECT_UNITS`) included."""
    candidates = list(dict.fromkeys(coord.values.ravel().tolist()))
    text = value_text(wanted).strip()
    for value in candidates:
        if value_text(value) == text or str(value) == text:
            return value
    number = _number_in_units(coord, name, text)
    if number is not None:
        for value in candidates:
            if (isinstance(value, (int, float)) and not isinstance(value, bool)
                    and math.isclose(float(value), number, rel_tol=1e-9, abs_tol=0.0)):
                return value
    units = coordinate_units(coord)
    hint = (f" (in {units}, or with a unit: {', '.join(SELECT_UNITS[units])})"
            if units in SELECT_UNITS else "")
    raise SelectionError(choice_message(f"value for {name}", text, [value_text(v) for v in candidates])
                         + hint, name=name, value=text, choices=[value_text(v) for v in candidates])


def coordinate_for_key(obj: xr.Dataset | xr.DataArray, name: str) -> str:
    """The coordinate that ``name`` names: ``name`` itself where ``obj`` has it, else the
    coordinate swept over the dotted config key ``name`` (its ``config_key`` attribute:
    ``mechanism.speed_rpm`` -> ``speed_rpm``); ``name`` unchanged where none is."""
    if name in obj.coords or "." not in name:
        return name
    return next((str(n) for n, c in obj.coords.items() if c.attrs.get("config_key") == name),
                name)


def parse_selection(obj: xr.Dataset | xr.DataArray,
                    items: Mapping[str, object] | Iterable[str] | None, *,
                    dims_only: bool = False) -> dict[str, object]:
    """Turn ``DIM=VALUE`` strings (or a mapping) into a validated ``.sel`` dict.

    Parameters
    ----------
    obj
        Dataset (or array) with sweep dimensions.
    items
        ``["B_coating=PTFE", "B_clearance=2.5e-4"]`` or ``{"B_coating": "PTFE"}``; a name
        may be the swept dotted config key (``joints.B.coating=PTFE``,
        :func:`coordinate_for_key`). Values match a coordinate value by text, or numerically for numbers.
    dims_only
        Accept only sweep dimensions, not other indexed coordinates
        (levels of a stacked ``case`` dimension).

    Returns
    -------
    dict
        Names mapped to coordinate values of ``obj``.

    Raises
    ------
    SelectionError
        Malformed item, unknown name or value; the message lists the choices.
    """
    if not items:
        return {}
    dims = sweep_dims(obj)
    names = [d for d in dims if d in obj.coords]
    if not dims_only:
        names += [str(n) for n in obj.xindexes
                  if n not in names and set(obj[n].dims) <= set(dims)]
    pairs = list(items.items()) if isinstance(items, Mapping) else []
    if not isinstance(items, Mapping):
        for item in items:
            name, sep, text = str(item).partition("=")
            if not sep:
                raise SelectionError(f"expected DIM=VALUE, got {item!r}", name=str(item),
                                     choices=names)
            pairs.append((name.strip(), text))
    out = {}
    for name, wanted in pairs:
        name = coordinate_for_key(obj, name)
        if name not in names and name in dims:
            # a zip group swept without labels: a dimension with no values to name
            others = f"; the dimensions with values: {', '.join(names)}" if names else ""
            raise SelectionError(f"sweep dimension {name!r} has no values to select by (a zip "
                                 f"group without labels: give the group labels in the sweep "
                                 f"file){others}", name=name, value=value_text(wanted),
                                 choices=names)
        if name not in names:
            raise SelectionError(choice_message("sweep dimension", name, names), name=name,
                                 value=value_text(wanted), choices=names)
        out[name] = _match_value(obj[name], name, wanted)
    return out


def select_cases(obj: xr.Dataset | xr.DataArray, items) -> xr.Dataset | xr.DataArray:
    """``obj.sel`` of the cases named by ``items`` (see ``parse_selection``)."""
    selection = parse_selection(obj, items)
    return obj.sel(selection) if selection else obj


# --------------------------------------------------------------------------- ideal joints

def file_config(ds: xr.Dataset) -> dict:
    """The case config a results file was made from: a run's or a life run's ``config``
    attribute, else the ``base`` of its sweep's ``sweep_config`` (a sweep, an ensemble, a
    reliability sweep: the base as resolved, ``--set`` items applied); {} where neither
    can be read as a mapping."""
    import yaml

    for name in ("config", "sweep_config"):
        if not ds.attrs.get(name):
            continue        # a sweep file has no run config: its base is in sweep_config
        try:
            doc = yaml.safe_load(str(ds.attrs[name])) or {}
        except yaml.YAMLError:
            continue
        if isinstance(doc, dict):
            base = doc.get("base", doc) if name == "sweep_config" else doc
            if isinstance(base, dict):
                return base
    return {}


def mechanism_kind(ds: xr.Dataset) -> str:
    """The mechanism (``mechanism.kind``) a results file was made with: its ``mechanism``
    attribute, else its config's (:func:`file_config`), else ``rssp`` (a file written before
    the key). A sweep over mechanisms names each, separated by spaces."""
    kind = ds.attrs.get("mechanism")
    if kind:
        return str(kind)
    mechanism = file_config(ds).get("mechanism")
    return str(mechanism.get("kind") or "rssp") if isinstance(mechanism, dict) else "rssp"


def is_planar(ds: xr.Dataset) -> bool:
    """Whether every case of ``ds`` is of a planar mechanism
    (``variables.PLANAR_MECHANISMS``): its joints' centres move in one plane of their socket
    frames."""
    from ..variables import PLANAR_MECHANISMS

    return all(kind in PLANAR_MECHANISMS for kind in mechanism_kind(ds).split())


def configured_clearances(ds: xr.Dataset) -> dict[str, float]:
    """Radial clearance [m] of each joint in the configuration text; empty when there is none.

    A case file holds its resolved config in the ``config`` attribute, a sweep file its
    base case under ``base`` of ``sweep_config``. A joint the text leaves out has its
    default, no clearance (joint O in a file written before it existed).
    """
    from ..config import section_clearance
    from ..schema import ConfigError, parse_yaml
    from ..variables import JOINTS

    for attr, section in (("config", None), ("sweep_config", "base")):
        try:
            config = parse_yaml(ds.attrs.get(attr) or "", attr) or {}
            joints = (config[section] if section else config)["joints"]
            return {**{name: 0.0 for name in JOINTS},
                    **{str(j): section_clearance(spec) for j, spec in joints.items()}}
        except (ConfigError, KeyError, TypeError, ValueError, AttributeError):
            continue
    return {}


def guide_gap(ds: xr.Dataset) -> tuple[float, float] | None:
    """The guide P's clearances (``clearance_y``, ``clearance_z``) [m] from the file's config
    (:func:`file_config`); None where the config text gives no guide with both."""
    try:
        spec = file_config(ds)["joints"]["P"]
        return float(spec["clearance_y"]), float(spec["clearance_z"])
    except (KeyError, TypeError, ValueError):
        return None


def joint_clearances(ds: xr.Dataset) -> xr.DataArray | None:
    """Radial clearance [m] of every joint in every case: (sweep dims..., joint), 0 for an
    ideal joint; ``None`` where the file says neither by a sweep coordinate nor its config.

    A swept clearance (the coordinate whose ``config_key`` is ``joints.<J>.clearance``) wins
    over the configured one.
    """
    if "joint" not in ds.coords:
        return None
    configured = configured_clearances(ds)
    per_joint = []
    for joint in ds["joint"].values:
        key = f"joints.{value_text(joint)}.clearance"
        swept = next((c for c in ds.coords.values() if c.attrs.get("config_key") == key), None)
        # a guide's two clearances (joints.P.clearance_y, _z): the smaller one
        pair = [c for c in ds.coords.values() if c.attrs.get("config_key") in (key + "_y", key + "_z")]
        if swept is not None:
            per_joint.append(xr.DataArray(swept.values.astype(float), dims=swept.dims))
        elif pair:
            arrays = [xr.DataArray(c.values.astype(float), dims=c.dims) for c in pair]
            if len(arrays) == 1 and value_text(joint) in configured:
                arrays.append(xr.DataArray(configured[value_text(joint)]))
            per_joint.append(xr.apply_ufunc(np.minimum, *arrays) if len(arrays) == 2 else arrays[0])
        elif value_text(joint) in configured:
            per_joint.append(xr.DataArray(configured[value_text(joint)]))
        else:
            return None
    return xr.concat(per_joint, dim="joint", coords="minimal").assign_coords(joint=ds["joint"])


def ideal_joints(ds: xr.Dataset) -> list[str]:
    """The joints that are ideal (no clearance) in every case of ``ds``, in ``joint`` order:
    their per-joint results are n/a throughout, so a report has no row and a figure no
    panel and no mention of them. Empty where ``ds`` does not say which joints have
    clearance (:func:`joint_clearances` is None)."""
    clearances = joint_clearances(ds)
    if clearances is None:
        return []
    return [value_text(j) for j in clearances["joint"].values
            if not float(clearances.sel(joint=j).max()) > 0.0]


def bushing_joints(ds: xr.Dataset) -> list[str]:
    """The joints that ran as elastic bushings (their ``joint_<J>_type`` attribute is
    ``bushing``, ``clearsweep.params.joint_attributes``), in ``joint`` order: no clearance,
    so ideal to the contact and wear figures, but their deflection is an orbit."""
    if "joint" not in ds.coords:
        return []
    return [value_text(j) for j in ds["joint"].values
            if elastic(ds.attrs.get(f"joint_{value_text(j)}_type", ""))]


def _drop_ideal_rows(rows: list[dict[str, object]], clearance: xr.DataArray | None) -> list:
    """``rows`` without those of an ideal joint (clearance 0) of the case ``clearance`` is of."""
    if clearance is None:
        return rows
    ideal = {value_text(j) for j in clearance["joint"].values
             if float(clearance.sel(joint=j)) == 0.0}
    return [r for r in rows if "joint" not in r or value_text(r["joint"]) not in ideal]


def is_ensemble(ds: xr.Dataset) -> bool:
    """Whether ``ds`` is an ensemble sweep with its statistics."""
    return has_member_statistics({str(d) for d in ds.dims}, {str(v) for v in ds.variables})


def design_dims(ds: xr.Dataset) -> tuple[str, ...]:
    """The sweep dimensions of ``ds`` but an ensemble's ``member``: one per design axis."""
    return tuple(d for d in sweep_dims(ds) if d != MEMBER_DIM)



#: What a results file holds, as :func:`results_kind` names it.
RESULTS_KINDS = tuple(_RESULTS_KINDS)


def results_kind(ds: xr.Dataset) -> str:
    """What the results file ``ds`` holds, one of :data:`RESULTS_KINDS`, by the rule of
    :func:`clearsweep.outputs.kind_of` (which tells a file on disk the same way)."""
    return kind_of(ds.attrs, {str(d) for d in ds.dims}, {str(v) for v in ds.variables})
