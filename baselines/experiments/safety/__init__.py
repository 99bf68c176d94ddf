"""What the safety filter changes for a controller, from benchmark runs with it off and on.

* :mod:`~baselines.experiments.safety.paired` and :mod:`~baselines.experiments.safety.compare`
  - ``python -m baselines.safety_compare``: the runs paired by (scenario, seed, pair);
* :mod:`~baselines.experiments.safety.figure` - ``python -m baselines.experiments.safety.figure``:
  the closest pass of every run, filter off against on;
* :mod:`~baselines.experiments.safety.swarm_report` and
  :mod:`~baselines.experiments.safety.nearest`: the swarm layer's tables from the
  ``swarm-safety`` suites, and its nearest-neighbour figure (docs/swarm-safety.md).

The runs come from ``python -m baselines.benchmark --suite safety`` (its safety table:
:func:`baselines.reporting.tables.safety_table`).
"""
