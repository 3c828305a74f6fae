"""Paper-style wear tables (Tables 4-6), per-case summaries and text reports.

Every function here takes a dataset as written by ``dataset.build_dataset``
(one case) or by the sweep driver (the same variables with extra sweep
dimensions in front, or only the summary variables for ``store: summary``)
and reduces over the case dimensions (``time``, ``angle``, ``polar``,
``azimuth``), so any sweep dimensions simply stay in the results. Units and
long names come from ``variables.SUMMARY_VARIABLES``.

Conventions (docs/physics.md section 5, paper Tables 4-6):

- Projection angles are the bin centres of ``wear_projection`` on
  (-180, 180] degrees. The worn bins are those whose depth exceeds
  ``WEAR_THRESHOLD_FRACTION`` of that axis's maximum; the wear range is the
  smallest arc on the circle that holds them all, and the minimum and maximum
  wear angles are its ends going up in angle, so that a worn region that
  straddles +-180 degrees reads as the few degrees the polar plot shows (the
  minimum angle then above the maximum), not as nearly 360.
- A (joint, axis) without any wear has depth 0 and NaN angles and range.
- Table 6 "reduction" is reference minus case; a negative wear-range
  reduction means that the range grew. Percentages are relative to the
  reference.

The package's modules: ``selection`` (sweep dimensions, cases, ``--select``), ``tables``
(the tables and their text, markdown, csv and json layout) and ``text`` (the run and
sweep summaries); their public names are importable from here, with those of
:mod:`clearsweep.motion` (spectra, period detection, the 0-1 test for chaos: pure
functions that the per-case summaries below ``analysis`` call too).
"""

from __future__ import annotations

from ..choices import REPORT_FORMATS  # noqa: F401
from ..ensemble import MEMBER_DIM  # noqa: F401
from ..motion import (  # noqa: F401
    CHAOS_THRESHOLD,
    HIGH_ORDER,
    MAX_PERIOD,
    PERIOD_NONE,
    PERIOD_UNKNOWN,
    detect_period,
    order_spectrum,
    spectrum_summary,
    zero_one_test,
)
from ..outputs import SAMPLE_DIM  # noqa: F401
from ..schema import close_matches  # noqa: F401
from ..summary import (  # noqa: F401
    PASS_THROUGH_VARIABLES,
    PERIODICITY_VARIABLES,
    SPECTRUM_VARIABLES,
    STATISTIC_VARIABLES,
    SUMMARY_ORDER,
    WEAR_TABLE_VARIABLES,
    WEAR_THRESHOLD_FRACTION,
    case_summary,
    crank_speed,
    motion_summary,
    poincare_points,
    settle_time,
    settled_revolutions,
    wear_table,
    with_attrs,
    worn_arc,
)
from .selection import (  # noqa: F401
    CASE_DIMS,
    QUANTITY_UNITS,
    RESULTS_KINDS,
    SelectionError,
    bushing_joints,
    choice_message,
    configured_clearances,
    coordinate_for_key,
    design_dims,
    file_config,
    guide_gap,
    ideal_joints,
    is_ensemble,
    is_planar,
    iter_cases,
    iter_points,
    joint_clearances,
    label_text,
    mechanism_kind,
    parse_selection,
    quantity_of,
    quantity_text,
    quantity_unit,
    results_kind,
    select_cases,
    sweep_dims,
    value_text,
)
from .tables import (  # noqa: F401
    COMPARED_METRICS,
    ENSEMBLE_METRICS,
    ensemble_comparisons,
    format_ensemble_comparisons,
    format_ensemble_report,
    format_ensemble_table,
    format_metric_table,
    format_reduction_table,
    format_statistics_table,
    format_wear_table,
    metric_table,
    reduction_table,
    report_summary,
)
from .text import (  # noqa: F401
    HEADLINE_METRICS,
    bushing_text,
    format_sweep_summary,
    run_summary_text,
    short_settled_window,
)
