"""``python -m train.imitate``: the imitation warm start, an analytic pair controller cloned
into a run's policy network with DAgger.

* :mod:`~train.imitate.dagger` - the DAgger rounds on one run (one seed);
* :mod:`~train.imitate.cli` - every seed, the seed summary and the command line.
"""
