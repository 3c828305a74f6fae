"""docs/mixed_clearances.md states what its study measures (issue 41 item 9): the run length
it names is configs/mixed_clearances.yaml's, each interval is the effect +- sqrt(h_m^2 +
h_r^2) of the terms its row prints, and its doubling table's verdicts are those of the moves
and half-widths it quotes, with the count of moves beyond their interval that the text gives.
The numbers themselves are docs/mixed_clearances.py's output for the study's files (the
study runs for half an hour on this project's 2-core machine: not a test)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
PAGE = (ROOT / "docs" / "mixed_clearances.md").read_text(encoding="utf-8")
CONFIG = yaml.safe_load((ROOT / "configs" / "mixed_clearances.yaml").read_text(encoding="utf-8"))
NUMBER = r"([+-]\d+\.\d+)"


def rows(first_cell: str, columns: int) -> list[list[str]]:
    """The cells of the page's table rows of ``columns`` cells whose first cell matches
    ``first_cell``."""
    out = []
    for line in PAGE.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and len(cells) == columns and re.fullmatch(first_cell, cells[0]):
            out.append(cells)
    return out


def test_the_page_names_the_configs_run_length():
    revolutions = CONFIG["base"]["solver"]["revolutions"]
    settle = CONFIG["base"]["metrics"]["settle_revolutions"]
    assert "duration" not in CONFIG["base"]["solver"]
    assert (f"**{revolutions} crank revolutions per case, the first\n{settle} set aside**" in PAGE
            or f"**{revolutions} crank revolutions per case, the first {settle} set aside**" in PAGE)
    assert f"`solver.revolutions: {revolutions}`" in PAGE


@pytest.mark.parametrize("first_cell", ["[ABOP]", "[ABOP] and [ABOP]"])
def test_each_interval_is_the_effect_plus_minus_the_root_sum_square_of_its_terms(first_cell):
    found = rows(first_cell, 7)
    assert len(found) == (4 if first_cell == "[ABOP]" else 6)
    for cells in found:
        value = float(cells[1])
        low, high = (float(x) for x in re.fullmatch(f"{NUMBER} \\.\\. {NUMBER}", cells[2]).groups())
        h_m, h_r = float(cells[3]), float(cells[4])
        half = math.hypot(h_m, h_r)
        # each printed to 3 decimals: the rounding of four numbers
        assert high - value == pytest.approx(half, abs=2.5e-3), cells
        assert value - low == pytest.approx(half, abs=2.5e-3), cells
        for at_speed in cells[5:7]:     # value (low .. high) at each speed
            v, lo, hi = (float(x) for x in re.fullmatch(
                f"{NUMBER} \\({NUMBER} \\.\\. {NUMBER}\\)", at_speed).groups())
            assert lo <= v <= hi


def test_the_doubling_table_verdicts_and_count_are_those_of_its_numbers():
    found = rows(r"(clearance at [ABOP]|[ABOP] and [ABOP])(, \d+ r/min)?", 6)
    assert len(found) == 30             # 4 effects and 6 pairs, averaged and at each speed
    outside = 0
    for cells in found:
        half = float(cells[2])
        before, after = (float(x) for x in re.fullmatch(f"{NUMBER} -> {NUMBER}", cells[3]).groups())
        moved = float(cells[4])
        assert moved == pytest.approx(after - before, abs=1.5e-3), cells
        within = cells[5] == "yes"
        assert cells[5] in ("yes", "**no**")
        if abs(abs(moved) - half) > 1.5e-3:       # a tie at the printed digits is not judged
            assert within == (abs(moved) <= half), cells
        outside += not within
    quoted = re.search(r"(\d+|no) of the 30 moved (?:outside|beyond)", PAGE)
    assert quoted, "the page does not say how many of the 30 moved beyond their interval"
    assert (0 if quoted.group(1) == "no" else int(quoted.group(1))) == outside
