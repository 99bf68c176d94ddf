"""Training one policy on a mix of tasks, and selecting it on several.

* :mod:`~train.mix.tasks` - the ``tasks`` and ``eval_tasks`` settings, resolved and checked;
* :mod:`~train.mix.env` - one SB3 VecEnv over the tasks' envs, rows concatenated;
* :mod:`~train.mix.evaluation` - per-task summaries and the one score a run selects by.

A run on one task is the mix of one (its evaluation task has the name ``""``).
"""
