"""Choices and limits that the command line declares, free of heavy imports.

Kept apart from the modules that use them (numpy, xarray, matplotlib, Numba)
so that ``cli.py`` can declare every command and its options without loading
any of those: each command imports what it runs when it runs.
"""

#: Output formats of ``clearsweep report`` (:mod:`clearsweep.analysis`).
REPORT_FORMATS = ("text", "markdown", "csv", "json")

#: Figure kinds of ``clearsweep plot`` (:mod:`clearsweep.plotting`).
KINDS = ("slider", "forces", "wear-map", "wear-polar", "orbit", "poincare", "sweep", "life",
         "reliability", "spectrum", "bifurcation", "effects", "dynamics-map")
#: Abscissae of time-series figures (``--kind bifurcation`` and ``dynamics-map`` take swept
#: keys instead).
#: The figure kinds whose ``--x`` is a swept key.
SWEPT_X_KINDS = ("bifurcation", "dynamics-map")
X_AXES = ("angle", "time")
#: Output file suffixes of figures (the suffix sets the format).
OUTPUT_SUFFIXES = (".png", ".pdf", ".svg")
#: Metric of ``--kind sweep`` when none is given.
DEFAULT_SWEEP_METRIC = "slider_acceleration_peak_settled"
#: Resolution of raster output [dots per inch].
FIGURE_DPI = 120
#: Resolutions ``--dpi`` accepts: beyond 1200 an 8 x 5 inch figure is 10^8 pixels.
DPI_RANGE = (10, 1200)

#: Most sweep points expanded without ``--yes`` (``max_cases``): every case is validated
#: before anything runs, so a grid of 10^7 points would spend hours just being checked.
MAX_CASES = 10_000
#: Most sweep points whatever the options: the plan holds every resolved case in memory.
MAX_CASES_ANY = 1_000_000

#: Where ``clearsweep sweep --backend`` runs the cases: this process / a process pool / Dask,
#: or batches on a CUDA device (:mod:`clearsweep.gpu`).
SWEEP_BACKENDS = ("processes", "cuda")

#: Most members of an ensemble or a reliability design, and most wear-map snapshots of a
#: life run: schema bounds, so that no config line asks for memory before the case bound
#: (MAX_CASES, lifted by --yes) is checked.
MAX_MEMBERS = 100_000
MAX_SNAPSHOTS = 10_000
#: Most dynamic blocks of a life run (``life.max_blocks``): its checkpoint, rewritten after
#: every block, grows by a row a block.
MAX_BLOCKS = 10_000
#: Most points a ``sample:`` section may draw, --yes or not (the points are drawn in memory).
MAX_SAMPLE_POINTS = 1_000_000

#: ``contact.damping``'s laws (docs/physics.md section 3.2), in the order of the kernel's law
#: codes (``core.contact.hysteresis_fraction``): the paper's first, the default.
DAMPING_LAWS = ("paper", "lankarani_nikravesh", "hunt_crossley", "flores", "gonthier",
                "carvalho_martins")
