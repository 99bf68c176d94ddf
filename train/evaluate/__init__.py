"""``python -m train.evaluate``: a trained pair policy next to the analytic controllers, with
the reproduction's rollout and metrics, on held-out seeds (:mod:`train.evaluate.cli`)."""
