"""The command-line experiments (each also runs as ``python -m baselines.<name>``).

* :mod:`~baselines.experiments.benchmark` - policies x scenarios x seeds, tables, figures;
* :mod:`~baselines.experiments.reproduce` - the paper's Sec. VI-A (the benchmark's paper suite);
* :mod:`~baselines.experiments.quadrotor_experiment` - Sec. VI-B with the quadrotor model;
* :mod:`~baselines.experiments.quadrotor_invariants` - physics invariants of the quadrotor.
"""
