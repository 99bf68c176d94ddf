"""Export a trained pair policy for a flight controller (``pairflock-export``,
docs/export.md).

* :mod:`~baselines.export.network` - the policy network of an SB3 model as arrays;
* :mod:`~baselines.export.onnx` - ``policy.onnx`` (opset 17), built from those arrays;
* :mod:`~baselines.export.c_interface` - the learning interface's encode/decode in C;
* :mod:`~baselines.export.c_source` - ``pairflock_policy.h`` / ``pairflock_policy.c``;
* :mod:`~baselines.export.contract` - ``contract.json``;
* :mod:`~baselines.export.verify` - observations from the task, onnxruntime, the C harness,
  the object's size;
* :mod:`~baselines.export.build` - load a policy, write and check an export folder;
* :mod:`~baselines.export.cli` - the command line.

The package imports nothing itself: :mod:`.cli` stays importable without the ``train`` and
``export`` extras, so that a missing one is reported as one line.
"""
