"""General infrastructure of the experiments and of training, below everything else in
:mod:`baselines` (the env never imports it):

* :mod:`~baselines.runtime.threads` - one thread per process, pinned before numpy loads;
* :mod:`~baselines.runtime.pool` - the process pool;
* :mod:`~baselines.runtime.files` - atomic files, CSV and JSON in a stable layout;
* :mod:`~baselines.runtime.folders` - result folders (complete, or marked INCOMPLETE);
* :mod:`~baselines.runtime.record` - the run record (``run.json``: versions, commit, command);
* :mod:`~baselines.runtime.cli` - the one error path of every command line;
* :mod:`~baselines.runtime.optional` - the optional dependencies, imported on first use.

The package imports nothing itself, so that a launcher can pin the threads before numpy
loads.
"""
