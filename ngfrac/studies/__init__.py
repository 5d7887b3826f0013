"""Studies: many runs of one scene.

- :func:`study` (``ngfrac study``): the product of ``--vary`` values, ``--zip`` pairs and a
  ``--refine`` sequence, each run an ordinary run folder, run by Dask (a local cluster of
  one-thread processes, or a running scheduler), resumable, with a table (``study.csv``) of
  headline numbers and Richardson/GCI error bars (docs/user-guide/studies.md);
- :func:`convergence_study`: one setting's values run one after the other in this process,
  with measured errors and fitted rates, for pytest files.

Importing this package does not import Dask; only running a study's scenes does.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

from .convergence import (LAST, StudyRow, StudyRun, StudyTable, convergence_study, fit_rate,
                          run_all_steps, scene_with)
from .engine import DaskMissing, StudyResult, run_study
from .plan import StudyPlan, plan_study
from .richardson import Richardson, richardson

__all__ = ["LAST", "DaskMissing", "Richardson", "StudyPlan", "StudyResult", "StudyRow",
           "StudyRun", "StudyTable", "convergence_study", "fit_rate", "plan_study",
           "richardson", "run_all_steps", "run_study", "scene_with", "study"]


def study(scene_path: str | Path, out_dir: str | Path, *, vary: Sequence[str] = (),
          zipped: Sequence[str] = (), overrides: Sequence[str] = (),
          refine: Sequence[str] = (), ratio: float = 2.0, levels: int = 3,
          workers: int | None = None, scheduler: str | None = None, client: Any = None,
          plots: bool = True) -> StudyResult:
    """Plan, validate and run a study: ``ngfrac study`` from Python.

    Parameters
    ----------
    scene_path : the scene file
    out_dir : the study folder
    vary, zipped, overrides, refine, ratio, levels : as :func:`~ngfrac.studies.plan.plan_study`
        (``vary=["phase_field.epsilon=0.03,0.015"]``)
    workers, scheduler, client : where the runs go (:func:`~ngfrac.studies.engine.run_study`);
        ``client`` a ``distributed.Client`` of your own
    plots : write ``plots/<key>.png``

    Returns
    -------
    StudyResult
        ``.rows``: the table (one dict per run, as in study.csv); ``.failed``; ``.summary()``.
    """
    plan = plan_study(scene_path, vary, zipped, overrides, refine, ratio, levels)
    return run_study(plan, out_dir, workers=workers, scheduler=scheduler, client=client,
                     plots=plots)
