"""Evaluation plumbing shared by the experiments and by training.

* :mod:`~baselines.evaluation.rollout` - batched episodes of any policy, traces and metrics;
* :mod:`~baselines.evaluation.jobs` - (scenario, policy, seed block) jobs and their backends;
* :mod:`~baselines.evaluation.specs` - CLI values, policy specs and scenario specs.

Imports :mod:`baselines.runtime`, :mod:`baselines.controllers` and :mod:`pairflock_env` only.
"""
