"""Training of pair policies with stable-baselines3 (PPO, SAC, TD3), and what uses them.

    python -m train --config train/configs/pair_n20_a50.yaml --out runs/pair_n20_a50
    python -m train --help

* :mod:`train.cli` (the command line), :mod:`train.settings` (what a run is made of, declared
  like the env config; YAML), :mod:`train.hyperparameters` (the algorithms and their SB3
  keywords), :mod:`train.run` (environment, model, logging, evaluation),
  :mod:`train.model`, :mod:`train.callbacks`, :mod:`train.checkpoint` (exact resume);
* :mod:`train.mix` - training and selecting on a mix of tasks;
* :mod:`train.evaluate` - ``python -m train.evaluate``: a held-out evaluation table;
* :mod:`train.imitate` - ``python -m train.imitate``: the imitation (DAgger) warm start;
* :mod:`train.sweep` - ``python -m train.sweep``: runs over seeds and settings.

Each command's ``__main__`` pins one thread per process before anything loads numpy or
torch; importing this package imports nothing. The training speed benchmark is
``benchmarks/bench_training.py``.
"""
