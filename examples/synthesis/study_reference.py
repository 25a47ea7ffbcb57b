"""A small design study: the reference design and a few random ones against the example task.

Run ``python examples/synthesis/study_reference.py``; it needs ``athenakin[synthesis]``.
The same from the shell: ``athenakin synthesize examples/synthesis/task_pancreas.toml
--designs 5``.
"""

from pathlib import Path

import athenakin as ak
from athenakin.synthesis import StudyOptions, Task, bounds_from_toml, evaluate, random_designs

HERE = Path(__file__).resolve().parent

task = Task.from_toml(HERE / "task_pancreas.toml")
bounds = bounds_from_toml(HERE / "task_pancreas.toml")
designs = [ak.Design.default(), *random_designs(5, bounds, seed=1)]

# Dask's local scheduler; pass scheduler="tcp://host:8786" to run on a cluster
df = evaluate(designs, task, samples=5_000, seed=0, options=StudyOptions(progress=False))
cols = ["design", "valid", "coverage", "coverage_mode", "size", "tip_error_max", "margin_min"]
print(df[cols].to_string(index=False, float_format=lambda x: f"{x:.4g}"))
