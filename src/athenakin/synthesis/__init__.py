"""Design studies: which ATHENA geometry serves a surgical task best, on one machine or a cluster.

* :mod:`._task` - the surgical task (:class:`Task`: RCM, cone of instrument
  directions, tip depths), its RCM frame and its samples;
* :mod:`._metrics` - the metrics of one design over the task (coverage, per-mode
  coverage, singularity margins, conditioning, stroke use, size, tip error and, when
  asked, the collision-free coverage and least clearance of the robot's bodies,
  :mod:`athenakin.collision` imported then);
* :mod:`._study` - :func:`evaluate`: a batch of designs on Dask (local scheduler
  by default, a ``distributed`` cluster by address or client, or any
  ``concurrent.futures.Executor``), Parquet chunks, resume, retries; its run settings
  :class:`StudyOptions` (with the collision check :class:`CollisionSpec`);
* :mod:`._search` - :func:`optimize`: NSGA-II (pymoo) over ``l1..l5`` and the
  strokes, the Pareto front and the reference design on it;
* :mod:`._patient` - the patient of a set-up plan (:class:`Patient`: closed surfaces by
  role read from ``patient.toml``) and the parametric :func:`phantom`;
* :mod:`._phantom` - the parametric :func:`phantom` (abdomen, pancreas, vessels, table);
* :mod:`._second_port` - a second port and its instrument (:class:`SecondPort`), a capsule
  the robot's bodies keep clear of;
* :mod:`._setup` - the decision of a set-up (:class:`Setup`: the port and the robot's
  base), :func:`evaluate_setup` and the set-up file;
* :mod:`._setup_plan` - :func:`plan_setup`: the set-up for a patient (NSGA-II on Dask);
* :mod:`._patient_environment` - the patient's surfaces as the bodies' obstacles, one set
  of rules for the coverage check and for :func:`setup_environment` (the app, teleop);
* :mod:`._cohort` - :func:`plan_cohort`: a cohort of patients as one resumable study;
* :mod:`.figures` - Pareto front, parameter coordinates, coverage maps (matplotlib).

Needs the ``synthesis`` extra (``pip install 'athenakin[synthesis]'``) for
:func:`evaluate` and :func:`optimize`; :class:`Task` needs only numpy.
Definitions and the scale-out arithmetic: ``docs/synthesis.md``.
"""

from ._cohort import plan_cohort
from ._errors import SchedulerUnreachableError, StudyMismatchError, SynthesisError, TaskFileError
from ._metrics import (
    COLLISION_COLUMNS,
    DEFAULT_COLLISION_SAMPLES,
    DEFAULT_ENCODER_RESOLUTION,
    DEFAULT_SAMPLES,
    METRIC_COLUMNS,
    PARAMETER_COLUMNS,
    CollisionSpec,
    collision_spec,
    design_from_row,
    evaluate_design,
    reachability,
    row_from_design,
)
from ._patient import (
    ROLES,
    OpenSurfaceError,
    Patient,
    PatientFileError,
    PatientMesh,
    write_patient,
)
from ._phantom import phantom
from ._scheduler import LOCAL_SCHEDULERS
from ._search import (
    DEFAULT_OBJECTIVES,
    SEARCH_VARIABLES,
    SearchResult,
    bounds_from_toml,
    check_bounds,
    check_constraints,
    default_bounds,
    optimize,
    pareto_mask,
    random_designs,
)
from ._second_port import (
    PORT_SKIN_TOLERANCE,
    PortOffSkinError,
    SecondPort,
    SecondPortError,
    read_second_ports,
)
from ._setup import (
    SETUP_COLUMNS,
    SETUP_VARIABLES,
    Setup,
    SetupOptions,
    covered_samples,
    default_setup_bounds,
    evaluate_setup,
    read_setup,
    reference_decision,
    setup_environment,
    setup_from_decision,
)
from ._setup_plan import SETUP_OBJECTIVES, SetupPlan, plan_setup
from ._study import CHUNK_SIZE, StudyOptions, design_rows, evaluate, read_study
from ._task import (
    MAX_TASK_SAMPLES,
    Task,
    TaskSamples,
    example_task_path,
    rcm_frame_from_axis,
    sample_task,
)

__all__ = [
    "ROLES",
    "OpenSurfaceError",
    "Patient",
    "PatientFileError",
    "PatientMesh",
    "phantom",
    "write_patient",
    "PORT_SKIN_TOLERANCE",
    "PortOffSkinError",
    "SecondPort",
    "SecondPortError",
    "read_second_ports",
    "SETUP_COLUMNS",
    "SETUP_OBJECTIVES",
    "SETUP_VARIABLES",
    "Setup",
    "SetupOptions",
    "SetupPlan",
    "covered_samples",
    "default_setup_bounds",
    "evaluate_setup",
    "plan_setup",
    "plan_cohort",
    "read_setup",
    "reference_decision",
    "setup_environment",
    "setup_from_decision",
    "CollisionSpec",
    "StudyOptions",
    "collision_spec",
    "COLLISION_COLUMNS",
    "DEFAULT_COLLISION_SAMPLES",
    "check_constraints",
    "DEFAULT_OBJECTIVES",
    "SEARCH_VARIABLES",
    "SearchResult",
    "bounds_from_toml",
    "check_bounds",
    "default_bounds",
    "optimize",
    "pareto_mask",
    "random_designs",
    "CHUNK_SIZE",
    "DEFAULT_ENCODER_RESOLUTION",
    "DEFAULT_SAMPLES",
    "LOCAL_SCHEDULERS",
    "MAX_TASK_SAMPLES",
    "METRIC_COLUMNS",
    "PARAMETER_COLUMNS",
    "SchedulerUnreachableError",
    "StudyMismatchError",
    "SynthesisError",
    "Task",
    "TaskFileError",
    "TaskSamples",
    "design_from_row",
    "design_rows",
    "evaluate",
    "evaluate_design",
    "example_task_path",
    "reachability",
    "rcm_frame_from_axis",
    "read_study",
    "row_from_design",
    "sample_task",
]
