"""The kernel reproduces tests/data/two_clearances_0p2s.npz bit for bit (see tests/regression.py)."""

from pathlib import Path

import numpy as np
from regression import simulate_reference, snapshot

REFERENCE = Path(__file__).parent / "data" / "two_clearances_0p2s.npz"

#: Variables added to a case dataset after the file was made; checked for presence here,
#: their values by their own tests (first_impact_time: tests/test_dopri5.py).
ADDED_SINCE = {"first_impact_time"}


def test_two_clearances_bit_identical():
    got = snapshot(simulate_reference())
    with np.load(REFERENCE) as ref:
        added = {k for k in got if k.partition("__")[2] in ADDED_SINCE}
        assert added and sorted(set(got) - added) == sorted(ref.files)
        for key in ref.files:
            # equal values (NaN where NaN), not close ones: a refactor must not move a bit
            assert np.array_equal(got[key], ref[key], equal_nan=ref[key].dtype.kind == "f"), key
