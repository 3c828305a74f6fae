"""Sobol' sensitivity indices of a sampling sweep (``sweep: sample: method: saltelli``).

First-order (S1) and total (ST) Sobol' indices of one output over the sampled inputs,
with 95 % confidence intervals, computed by SALib (``SALib.analyze.sobol``: Saltelli's
and Jansen's estimators, bootstrap intervals) from the Saltelli design that the sweep ran.
The design (method, base points, seed, ranges) is read back from the sweep file's
``sweep_config`` attribute, so the points need not be trusted to be in design order by
anything but the sweep's own ``sample`` dimension.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr
import yaml
from matplotlib.figure import Figure

from .analysis import SAMPLE_DIM, SelectionError, choice_message, value_text
from .ensemble import CONFIDENCE_LEVEL, MEMBER_DIM

#: Bootstrap resamples of SALib's confidence intervals.
BOOTSTRAP_RESAMPLES = 1000
#: An input whose total index ST may reach this (the upper end of its 95 % interval) is
#: influential and needs a rank; below it an input explains under 5 % of the output's
#: variance, a common screening threshold, and the order among such inputs is not asked.
INFLUENTIAL_ST = 0.05
#: An output whose spread over the sample is at most this fraction of its largest magnitude
#: does not vary: rounding error (float64's is 2.2e-16 per operation) is all that moves it,
#: and SALib turned it into indices of 0.000 +- 0.000 (exactly constant, with a raw
#: RuntimeWarning) or into noise such as ST = 1.5 +- 0.7 (1e-15 of the value).
CONSTANT_SPREAD = 1e-12


class SensitivityError(ValueError):
    """A file or output that Sobol' indices cannot be computed from."""


@dataclass(frozen=True)
class SobolIndices:
    """First-order and total indices of one output, per input, with 95 % half-widths."""

    names: tuple[str, ...]
    S1: np.ndarray
    S1_conf: np.ndarray
    ST: np.ndarray
    ST_conf: np.ndarray
    output: str = ""
    samples: int = 0
    #: base points n of the Saltelli design (``sweep.sample.n``); 0: not known
    base_points: int = 0
    #: what a figure calls the output: its long name and the slice (``""``: ``output``)
    output_label: str = ""

    def ranking(self) -> list[int]:
        """Input positions by total index ST, largest first."""
        return [int(i) for i in np.argsort(-self.ST, kind="stable")]

    def unranked_pairs(self) -> list[tuple[int, int]]:
        """Neighbours in the ST ranking that the intervals cannot order.

        The inputs are ranked by ST. Each influential input (the upper end of its ST
        interval at least :data:`INFLUENTIAL_ST`) must be told from the next one down,
        influential or not: their 95 % ST intervals must not overlap. Inputs that are all
        below the threshold need no order among themselves.
        """
        order = self.ranking()
        return [(upper, lower) for upper, lower in zip(order, order[1:])
                if self.ST[upper] + self.ST_conf[upper] >= INFLUENTIAL_ST
                and self.ST[upper] - self.ST_conf[upper] <= self.ST[lower] + self.ST_conf[lower]]

    def ranking_warning(self) -> str | None:
        """One line when the intervals are too wide to rank the inputs (see
        :meth:`unranked_pairs`), naming n and a larger n to try; None when they rank."""
        pairs = self.unranked_pairs()
        if not pairs:
            return None
        i, j = pairs[0]
        gap = self.ST[i] - self.ST[j]
        width = self.ST_conf[i] + self.ST_conf[j]
        # the half-widths shrink as 1 / sqrt(n): n (width / gap)^2 separates the pair
        factor = min(max((width / gap) ** 2 if gap > 0 else 16.0, 2.0), 16.0)
        n = self.base_points
        suggest = 2 ** math.ceil(math.log2(n * factor * 1.2)) if n else 0
        return (f"the 95 % intervals are too wide to rank the inputs: ST of {self.names[i]} "
                f"{self.ST[i]:.3f} +- {self.ST_conf[i]:.3f} overlaps ST of {self.names[j]} "
                f"{self.ST[j]:.3f} +- {self.ST_conf[j]:.3f}"
                + (f" with n = {n} base points; try sweep.sample.n: {suggest} (intervals "
                   f"shrink as 1/sqrt(n))" if n else "; try a larger sweep.sample.n"))

    def to_dataset(self) -> xr.Dataset:
        dims = ("input",)
        attrs = {"confidence_level": CONFIDENCE_LEVEL,
                 "ci_method": f"bootstrap, {BOOTSTRAP_RESAMPLES} resamples (SALib)"}
        return xr.Dataset({
            "S1": (dims, self.S1, {"long_name": "first-order Sobol index", "units": "1"}),
            "S1_conf": (dims, self.S1_conf, {"long_name": "half-width of the S1 confidence "
                                             "interval", "units": "1", **attrs}),
            "ST": (dims, self.ST, {"long_name": "total Sobol index", "units": "1"}),
            "ST_conf": (dims, self.ST_conf, {"long_name": "half-width of the ST confidence "
                                             "interval", "units": "1", **attrs}),
        }, coords={"input": list(self.names)}, attrs={"output": self.output, "samples": self.samples})


def sobol_indices(names: Sequence[str], bounds: Sequence[Sequence[float]], y: np.ndarray, *,
                  second_order: bool = False, seed: int = 0) -> SobolIndices:
    """Sobol' indices of outputs ``y`` of a Saltelli design (``SALib.sample.sobol``) over
    ``bounds``; intervals: SALib's bootstrap at 95 %, seeded."""
    from SALib.analyze import sobol

    problem = {"num_vars": len(names), "names": list(names), "bounds": [list(b) for b in bounds]}
    y = np.asarray(y, dtype=float)
    result = sobol.analyze(problem, y, calc_second_order=second_order, conf_level=CONFIDENCE_LEVEL,
                           num_resamples=BOOTSTRAP_RESAMPLES, seed=seed)
    return SobolIndices(tuple(names), np.asarray(result["S1"]), np.asarray(result["S1_conf"]),
                        np.asarray(result["ST"]), np.asarray(result["ST_conf"]), samples=len(y))


def sample_design(ds: xr.Dataset) -> dict[str, Any]:
    """The ``sweep.sample`` section of the sweep that wrote ``ds``; it must be a Saltelli design."""
    text = ds.attrs.get("sweep_config")
    try:
        doc = yaml.safe_load(str(text)) if text else None
    except yaml.YAMLError as exc:
        raise SensitivityError(f"its sweep_config attribute is not readable YAML "
                               f"({getattr(exc, 'problem', None) or type(exc).__name__}): "
                               "the file was changed after the sweep wrote it") from None
    sweep = doc.get("sweep") if isinstance(doc, Mapping) else None
    spec = sweep.get("sample") if isinstance(sweep, Mapping) else None
    if SAMPLE_DIM not in ds.dims or not isinstance(spec, Mapping):
        raise SensitivityError("not a sampling sweep: Sobol' indices need a sweep with "
                               "'sweep: sample: method: saltelli'")
    if spec.get("method") != "saltelli":
        raise SensitivityError(f"the sweep sampled with method {spec.get('method')!r}; Sobol' "
                               "indices need the Saltelli design (sweep.sample.method: saltelli)")
    ranges, n, seed = spec.get("ranges"), spec.get("n"), spec.get("seed", 0)
    if (not isinstance(ranges, Mapping) or not ranges or not isinstance(n, int)
            or not _is_count(n) or not _is_count(seed)
            or not all(isinstance(b, list) and len(b) == 2
                       and all(isinstance(v, (int, float)) for v in b) for b in ranges.values())):
        raise SensitivityError("its sweep_config attribute holds no readable Saltelli design "
                               "(sweep.sample: n, seed and ranges of [low, high])")
    points = n * (2 * len(ranges) + 2 if spec.get("second_order") else len(ranges) + 2)
    if ds.sizes[SAMPLE_DIM] != points:
        raise SensitivityError(
            f"the design in its sweep_config (n = {n} base points over {len(ranges)} inputs: "
            f"{points} points) does not match the {ds.sizes[SAMPLE_DIM]} samples it holds")
    return dict(spec)


def _is_count(value: Any) -> bool:
    """A non-negative integer, not a bool."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def output_values(ds: xr.Dataset, output: str, select: Sequence[str] = ()) -> xr.DataArray:
    """The output over ``sample``: the ensemble mean where the file is an ensemble, other
    dimensions (``joint``) fixed by ``select`` items ``DIM=VALUE``."""
    name = output + "_mean" if MEMBER_DIM in ds.dims and output + "_mean" in ds else output
    names = [str(n) for n, v in ds.data_vars.items() if v.dims and v.dims[0] == SAMPLE_DIM
             and v.dtype.kind in "fiu"]
    if name not in ds:
        raise SelectionError(choice_message("output", output, names), name=output, choices=names)
    if ds[name].dtype.kind not in "fiu":     # status, message: text
        raise SelectionError(f"output {output!r} is text, not a number; choose from: "
                             f"{', '.join(names)}", name=output, choices=names)
    values = ds[name]
    chosen: dict[str, Any] = {}
    for item in select:
        dim, _, wanted = str(item).partition("=")
        if dim not in values.dims or dim == SAMPLE_DIM or dim not in ds.coords:
            others = [str(d) for d in values.dims if d != SAMPLE_DIM]
            raise SelectionError(choice_message("dimension", dim, others), name=dim, choices=others)
        texts = [value_text(v) for v in ds[dim].values]
        if wanted.strip() not in texts:
            raise SelectionError(choice_message(f"value for {dim}", wanted, texts), name=dim,
                                 value=wanted, choices=texts)
        chosen[dim] = ds[dim].values[texts.index(wanted.strip())]
    values = values.sel(chosen) if chosen else values
    extra = [d for d in values.dims if d != SAMPLE_DIM]
    if extra:
        raise SelectionError(f"{output} also varies over {', '.join(map(str, extra))}: choose one "
                             f"value with --select (e.g. --select {extra[0]}="
                             f"{value_text(ds[extra[0]].values[-1]) if extra[0] in ds.coords else 0})")
    return values


def sweep_indices(ds: xr.Dataset, output: str, select: Sequence[str] = ()) -> SobolIndices:
    """Sobol' indices of ``output`` of the Saltelli sampling sweep ``ds``.

    Raises
    ------
    SensitivityError
        Not a Saltelli sampling sweep, or a case without a value (a failed case: the
        estimators need every point of the design).
    """
    spec = sample_design(ds)
    values = output_values(ds, output, select)
    y = values.transpose(SAMPLE_DIM).values.astype(float)
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise SensitivityError(f"{bad.size} of {y.size} sample points have no finite {output} "
                               f"(failed cases, e.g. sample {int(bad[0])}); the Sobol' estimators "
                               "need every point of the design")
    spread, size = float(np.ptp(y)), float(np.max(np.abs(y)))
    if spread <= CONSTANT_SPREAD * size:
        how = (f"every one is {y[0]:.6g}" if spread == 0.0 else
               f"it spans {spread:.3g}, rounding error on values of {size:.3g}")
        raise SensitivityError(f"{output} does not vary over the {y.size} sample points ({how}): "
                               "no input changes it, and Sobol' indices, shares of its variance, "
                               "are undefined; choose an output that varies")
    ranges = spec["ranges"]
    result = sobol_indices(list(ranges), list(ranges.values()), y,
                           second_order=bool(spec.get("second_order", False)),
                           seed=int(spec.get("seed", 0)))
    label = str(values.attrs.get("long_name") or output)
    if select:
        label += f" ({', '.join(str(item) for item in select)})"
    return SobolIndices(result.names, result.S1, result.S1_conf, result.ST, result.ST_conf,
                        output=output, samples=result.samples, base_points=int(spec.get("n", 0)),
                        output_label=label)


def format_indices(result: SobolIndices) -> str:
    """A text table: input, S1 -+ half-width, ST -+ half-width."""
    width = max(len("input"), *(len(n) for n in result.names))
    lines = [f"Sobol' indices of {result.output} ({result.samples} cases; 95% bootstrap "
             f"confidence half-widths, {BOOTSTRAP_RESAMPLES} resamples)",
             f"{'input'.ljust(width)}  {'S1':>17}  {'ST':>17}"]
    for i, name in enumerate(result.names):
        lines.append(f"{name.ljust(width)}  {result.S1[i]:>8.3f} +- {result.S1_conf[i]:<5.3f}  "
                     f"{result.ST[i]:>8.3f} +- {result.ST_conf[i]:<5.3f}")
    return "\n".join([lines[0], ranking_text(result), *lines[1:]])


def ranking_text(result: SobolIndices) -> str:
    """The inputs by total index, largest first ("?" where the intervals cannot tell two
    apart), then the negligible ones: ST interval below :data:`INFLUENTIAL_ST` and told
    apart from every ranked input."""
    unordered = result.unranked_pairs()
    upper = result.ST + result.ST_conf
    ranked: list[int] = []
    for i in result.ranking():
        if upper[i] >= INFLUENTIAL_ST or (ranked and (ranked[-1], i) in unordered):
            ranked.append(i)
    parts = []
    for k, i in enumerate(ranked):
        if k:
            parts.append(" ? " if (ranked[k - 1], i) in unordered else " > ")
        parts.append(result.names[i])
    text = "ranked by ST: " + ("".join(parts) or "no input")
    rest = [result.names[i] for i in result.ranking() if i not in ranked]
    if rest:
        text += f" (ST < {INFLUENTIAL_ST:g}: {', '.join(rest)})"
    return text


def indices_figure(result: SobolIndices) -> Figure:
    """Horizontal bars of S1 and ST per input (the largest ST on top) with their 95 %
    confidence intervals as error bars; the input names, dotted config keys, read along
    the bars' axis, where they have room."""
    fig = Figure(figsize=(7, 1.6 + 0.55 * len(result.names)), layout="constrained")
    ax = fig.add_subplot()
    order = result.ranking()[::-1]
    y = np.arange(len(order))
    ax.barh(y + 0.2, result.S1[order], 0.4, xerr=result.S1_conf[order], capsize=3,
            label="first order S1")
    ax.barh(y - 0.2, result.ST[order], 0.4, xerr=result.ST_conf[order], capsize=3,
            label="total ST")
    ax.set_yticks(y, [result.names[i] for i in order])
    ax.set_xlabel("Sobol index [-]")
    ax.axvline(0.0, color="0.5", lw=0.8)
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize="small", loc="lower right")
    cases = f"{result.samples} cases" + (f", n = {result.base_points}" if result.base_points else "")
    fig.suptitle(f"Sobol' indices of {result.output_label or result.output} ({cases})\n"
                 "bars: 95% confidence intervals", fontsize="medium", wrap=True)
    return fig


def save_figure(fig: Figure, path, dpi: int = 150) -> None:
    """Save ``fig`` to ``path`` (format from the suffix), atomically."""
    from pathlib import Path

    from .dataset import replaced_on_success
    from .outputs import figure_metadata

    path = Path(path)
    fmt = path.suffix.lower()[1:] or "png"
    with replaced_on_success(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt, metadata=figure_metadata(fmt))
