"""Parameter sweeps: plan, run, backends, worker, parts, assemble (docs/physics.md section 9).

Modules, each importing only those after it (``clearsweep.sweep`` is the public
:func:`run.run_sweep`; this package is named ``sweeping`` so that importing it
never shadows that function on ``clearsweep``):

- :mod:`.run`: drives a plan through a backend: progress, interrupts, resume.
- :mod:`.plan`: sweep files -> a plan of cases (grid, zip, skip), validated.
- :mod:`.backends`: where cases run: serial, process pool, Dask.
- :mod:`.worker`: runs one case in a worker and writes its part.
- :mod:`.assemble`: parts -> one labelled sweep netCDF, case by case, in bounded memory.
- :mod:`.parts`: one finished case per part file; the resume ledger and its lock.
- :mod:`.stores`: what each ``store:`` does with its cases (checks, members, case
  functions, what the file gets added), the ensemble and the CUDA batch, said once.

Sweep file
----------
::

    name: coating_clearance        # optional; default: the file's stem
    store: full                    # full (time series + summaries) | summary | life (each
                                   # case a service-life run, stored as its life summary)
    base: case.yaml                # a case config: inline mapping, or a path relative to this file
    sweep:
      grid:                        # cartesian product; one dimension per key
        joints.B.coating: [none, MoS2, lead, PTFE]
        joints.B.clearance: [1.0e-4, 2.5e-4, 5.0e-4]
      zip:                         # each group is ONE dimension; its keys vary together
        - name: clearance_joints   # optional dimension name
          labels: [B, AB]          # optional index values of that dimension
          joints.A.clearance: [0.0, 2.5e-4]
      skip:                        # optional; matching points are not run (status "skipped")
        - {B_coating: none, B_clearance: 1.0e-4}

    sweep:                         # or: points drawn over continuous ranges
      sample:                      # ONE dimension "sample"; every key a coordinate along it
        method: saltelli           # sobol | lhs (scipy.stats.qmc) | saltelli (SALib)
        n: 64                      # points; for saltelli base points: n (D + 2) cases
        seed: 1                    # the same seed draws the same points
        second_order: false        # saltelli only: n (2 D + 2) cases, second-order indices
        ranges:
          joints.B.clearance: [1.0e-4, 5.0e-4]
          mechanism.speed_rpm: [40.0, 80.0]

Keys are dotted paths of the case configuration (docs/architecture.md).
A ``sample:`` section (it may stand beside grid and zip axes) is one dimension
``sample`` whose index is the point number; ``clearsweep sensitivity`` computes
Sobol' indices from a ``saltelli`` sample (:mod:`clearsweep.sensitivity`).
A base with an ensemble (``ensemble: {members: 16, seed: 1, perturb: {...}}``,
docs/physics.md section 10) adds a last dimension ``member`` (0 .. members - 1): every
member is an ordinary case, and the file gains the ensemble statistics
(:mod:`clearsweep.ensemble`: ``<name>_mean``, ``_std``, ``_ci_low``, ``_ci_high``,
``members_ok``). ``ensemble.member`` and ``ensemble.members`` cannot be swept.
Command-line ``--set KEY=VALUE`` overrides apply to the base; a key that the
sweep varies cannot be overridden.

Naming
------
Each grid key becomes a dimension whose index coordinate holds the values as
given (material names stay strings, so ``ds.sel(B_coating="PTFE")`` works).
Its name is the dotted key with the first component dropped when that is
``joints``, ``mechanism``, ``contact``, ``friction``, ``wear`` or ``solver``,
and the rest joined with ``_``: ``joints.B.coating`` -> ``B_coating``,
``joints.B.clearance`` -> ``B_clearance``, ``mechanism.speed_rpm`` ->
``speed_rpm``, ``wear.amplification`` -> ``amplification``. Keys whose short
names collide with each other or with a variable or coordinate of a case
(``friction.enabled`` and ``wear.enabled``) get the full path joined with
``_`` (``friction_enabled``, ``wear_enabled``).

A zip group becomes one dimension named by its ``name:``, else by its first
key's name + ``_zip``; every key of the group is a non-index coordinate along
it, and ``labels:``, when given, is its index coordinate. Values that are not
all numbers, all booleans or all strings (``null``, lists) are stored as their
JSON text. Dimensions come in file order: grid keys, then zip groups.

A ``skip:`` rule maps coordinate names (or dotted keys) to a value or a list
of values; a point matching every entry of a rule is not run and is stored
with ``status = "skipped"`` (the paper sweep skips coatings on ideal joints).

Running
-------
:func:`expand` validates every case with :func:`clearsweep.config.load_config`
before anything runs: an invalid combination raises ``ConfigError`` naming
the sweep key, its value and the case. :func:`run_sweep` then runs the cases
that have no part yet, serially (one worker), on a process pool
(``forkserver`` or ``spawn``: Numba and ``fork`` do not mix) or on a Dask
``distributed`` client given by the caller (the library never starts a
cluster; ``clearsweep sweep --dask-local N`` does, and closes it). Each
finished case is written at once to ``OUT.parts/<hash>.nc``
(:mod:`clearsweep.sweeping.parts`): by the pool worker that ran it, or by the driver
for Dask workers, which may not share its disk. The final file is assembled
from the parts in sweep order, one case at a time, so results do not depend
on the backend, the number of workers or the completion order.

A case whose simulation does not end with status ``ok``, or raises, is
stored with its status, a ``message`` and fill values (NaN), and the sweep
goes on. A worker process of the sweep's own pool that dies (killed, out of
memory) takes the cases in flight with it: the pool is replaced and those
cases run again, one at a time; one that kills its worker again is stored
with status ``error`` and the reason. A pool passed by the caller cannot be
replaced: its death stops the sweep (:class:`SweepFailed`), finished cases
kept.
"""

from .assemble import SweepSlot, write_sweep_netcdf
from .backends import process_pool
from .guard import UnguardedScript
from .parts import PartStore, StoreError, case_hash, parts_dir_for
from .plan import STORE_MODES, Axis, Case, SweepPlan, dimension_name, expand
from .run import TIMING_VARIABLES, CasesFailedWarning, SweepFailed, SweepInterrupted, drop_timing, run_sweep

__all__ = ["Axis", "Case", "SweepPlan", "SweepInterrupted", "SweepFailed", "StoreError",
           "PartStore", "SweepSlot", "expand", "run_sweep", "drop_timing", "dimension_name",
           "process_pool", "parts_dir_for", "case_hash", "write_sweep_netcdf", "STORE_MODES",
           "TIMING_VARIABLES", "CasesFailedWarning", "UnguardedScript"]
