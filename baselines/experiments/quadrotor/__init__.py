"""The paper's 10-quadrotor experiment (Sec. VI-B), with the particle model side by side.

* :mod:`~baselines.experiments.quadrotor.experiment` - ``python -m
  baselines.quadrotor_experiment``: the runs, the summary, the criteria and the figures;
* :mod:`~baselines.experiments.quadrotor.runs` - one job (vehicle model, policy, seeds) and
  the Sec. VI-B measurements of each run;
* :mod:`~baselines.experiments.quadrotor.criteria` - the Sec. VI-B criteria and their check;
* :mod:`~baselines.experiments.quadrotor.figures` - the figures in the style of Figs. 15-20;
* :mod:`~baselines.experiments.quadrotor.invariants` - ``python -m
  baselines.quadrotor_invariants``: physics invariants of the quadrotor model;
* :mod:`~baselines.experiments.quadrotor.paired` and
  :mod:`~baselines.experiments.quadrotor.compare` - ``python -m baselines.quadrotor_compare``:
  two runs compared seed by seed.
"""
