"""``python -m train.sweep``: training runs over seeds and settings, with statistics over
seeds (docs/sweeps.md).

* :mod:`~train.sweep.cli` - the command line, and a sweep's session;
* :mod:`~train.sweep.plan` - the sweep's definition, expanded into trials;
* :mod:`~train.sweep.trial` - one trial: train or resume its run, collect its result;
* :mod:`~train.sweep.local` and :mod:`~train.sweep.ray` - the two backends (worker processes
  through :mod:`~train.sweep.worker`, or Ray Tune);
* :mod:`~train.sweep.report` - ``sweep.csv``, ``summary.md`` and ``curves.png``.
"""
