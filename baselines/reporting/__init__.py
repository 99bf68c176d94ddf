"""What the experiments and training report: tables, acceptance criteria, figures, video.

* :mod:`~baselines.reporting.tables` - the one markdown summary-table writer and its cells;
* :mod:`~baselines.reporting.criteria` - every acceptance threshold and its checks;
* :mod:`~baselines.reporting.figures` - paper-style figures (Figs. 4-16);
* :mod:`~baselines.reporting.benchmark_figures` - the benchmark's figure set and traces file;
* :mod:`~baselines.reporting.quadrotor_figures` - the quadrotor experiment's figures;
* :mod:`~baselines.reporting.video` - episode videos.

Imports :mod:`baselines.evaluation`, :mod:`baselines.controllers` and :mod:`pairflock_env`.
"""
