"""The experiments, one folder each, with their command lines (launched as ``python -m
baselines.<command>``):

* :mod:`~baselines.experiments.benchmark` - policies x scenarios x seeds, tables, figures and
  video (``benchmark``); its ``paper`` suite is the reproduction of Sec. VI-A (``reproduce``);
* :mod:`~baselines.experiments.quadrotor` - Sec. VI-B with the quadrotor model
  (``quadrotor_experiment``), its physics invariants (``quadrotor_invariants``) and the
  seed-by-seed comparison of two runs (``quadrotor_compare``);
* :mod:`~baselines.experiments.safety` - the safety filter off against on, run by run
  (``safety_compare``), and the closest-pass figure;
* :mod:`~baselines.experiments.paired` - what the two paired comparisons share.

Experiments import everything below them (runtime, controllers, evaluation, reporting);
nothing else imports an experiment.
"""
