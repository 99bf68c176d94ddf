"""Evaluation plumbing shared by the experiments and by training.

* :mod:`~baselines.evaluation.rollout` - batched episodes of any policy, traces and metrics;
* :mod:`~baselines.evaluation.jobs` - (scenario, policy, seed block) jobs and their backends;
* :mod:`~baselines.evaluation.parallel` - thread pinning and the process pool;
* :mod:`~baselines.evaluation.specs` - CLI values, policy specs and scenario specs;
* :mod:`~baselines.evaluation.io` - atomic files, result folders and run records.

Imports :mod:`baselines.controllers` and :mod:`pairflock_env` only. The package itself
imports nothing, so :func:`~baselines.evaluation.parallel.pin_threads` can run before numpy
loads.
"""
