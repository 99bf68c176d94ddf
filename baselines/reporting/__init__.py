"""What the experiments and training report: tables, statistics, acceptance criteria, figures,
video.

* :mod:`~baselines.reporting.tables` - the one markdown summary-table writer and its cells,
  and the safety filter's table;
* :mod:`~baselines.reporting.stats` - the bootstrap, the interquartile mean, McNemar's test;
* :mod:`~baselines.reporting.criteria` - the acceptance thresholds of the benchmark and of
  training, and their checks;
* :mod:`~baselines.reporting.figures` - paper-style figures (Figs. 4-16);
* :mod:`~baselines.reporting.video` - episode videos.

Imports :mod:`baselines.runtime`, :mod:`baselines.evaluation`, :mod:`baselines.controllers`
and :mod:`pairflock_env`. What belongs to one experiment lives in its folder of
:mod:`baselines.experiments`.
"""
