"""Training CLI for pairflock pair policies (stable-baselines3 PPO, SAC, TD3).

    python -m train --config train/configs/pair_n20_a50.yaml --out runs/pair_n20_a50
    python -m train --help

Modules: :mod:`train.cli` (arguments), :mod:`train.settings` (what a run is made of, YAML),
:mod:`train.run` (environment, model, logging, evaluation), :mod:`train.callbacks`,
:mod:`train.checkpoint` (exact resume), :mod:`train.evaluate` (held-out evaluation table),
:mod:`train.throughput` (native VecEnv vs the PettingZoo -> SuperSuit route).
Importing this package does not import SB3 or torch.
"""
