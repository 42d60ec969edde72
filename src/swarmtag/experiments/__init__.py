"""The experiments of SPEC §6: study specs, a resumable parallel runner and a results store.

::

    from swarmtag.experiments import load_study, run_study

    study = load_study("controller-selection")      # or a path: load_study("my-study.toml")
    result = run_study(study, out_dir="out", quick=True)
    result.metrics_paths    # {"default": Path("out/controller-selection/default/metrics.json")}

- ``Study`` / ``Scale``: a validated study file (``spec.py``); ``STUDIES``
  and ``load_study``: the shipped studies, ``REPRODUCED`` those of SPEC §6
  (``registry.py``);
- ``ResultsStore`` / ``RunKey``: every run's rows in one DuckDB file, one
  transaction per chunk (``store.py``; the ``experiments`` extra);
- ``ChunkJob`` / ``simulate_chunk``: the unit of work (``chunks.py``);
  local process pool or Dask cluster (``execute.py``);
- ``run_study``: chunks of missing runs in parallel, stored as they finish,
  metrics per scale (``runner.py``; a warehouse scale's over the orders
  placed after its warm-up, ``kpi_log``);
- ``reproduce``: every study at ``seeds`` master seeds (``seeded_study``:
  its seed + 0 .. K-1) and the report (``reproduce.py``); ``DIRECTIONS``:
  SPEC §6's published directions as ``Direction`` records with a ``Shift``,
  ``Close`` or ``Trend`` rule (``directions.py``), judged per seed and
  summarised over the seeds as ``ClaimSummary`` records (``robustness.py``).

See docs/experiments.md for the study file format, the store's schema and how resume works.
"""

from __future__ import annotations

from swarmtag.experiments.chunks import ChunkJob, simulate_chunk, split_runs
from swarmtag.experiments.directions import DIRECTIONS, Close, Direction, Shift, Trend
from swarmtag.experiments.registry import REPRODUCED, STUDIES, load_study, study_path
from swarmtag.experiments.reproduce import (
    MAX_SEEDS,
    Reproduction,
    StudyRun,
    reproduce,
    seed_folder,
    seeded_study,
)
from swarmtag.experiments.robustness import ClaimSummary
from swarmtag.experiments.runner import (
    QUICK_RESAMPLES,
    STORE_NAME,
    StudyResult,
    kpi_log,
    plan_chunks,
    run_study,
    study_key,
)
from swarmtag.experiments.spec import DEFAULT_SCALE, URGENCY_MODELS, Scale, Study, read_study_file
from swarmtag.experiments.store import KEY_COLUMNS, SCHEMA_SQL, ResultsStore, RunKey

__all__ = [
    "DEFAULT_SCALE",
    "DIRECTIONS",
    "KEY_COLUMNS",
    "MAX_SEEDS",
    "QUICK_RESAMPLES",
    "REPRODUCED",
    "SCHEMA_SQL",
    "STORE_NAME",
    "STUDIES",
    "URGENCY_MODELS",
    "ChunkJob",
    "ClaimSummary",
    "Close",
    "Direction",
    "Reproduction",
    "ResultsStore",
    "RunKey",
    "Scale",
    "Shift",
    "Study",
    "StudyResult",
    "StudyRun",
    "Trend",
    "kpi_log",
    "load_study",
    "plan_chunks",
    "read_study_file",
    "reproduce",
    "run_study",
    "seed_folder",
    "seeded_study",
    "simulate_chunk",
    "split_runs",
    "study_key",
    "study_path",
]
