"""A stable-baselines3 policy as plain arrays: the layers behind ``predict(obs,
deterministic=True)``, read from the model's torch modules.

:func:`policy_network` walks the actor of a PPO, SAC or TD3 model and returns a
:class:`PolicyNetwork`: dense layers (float32 weights and biases, one activation each) and the
transform SB3's ``predict`` applies to a Box action (``"clip"`` to the box, or ``"unscale"``:
a squashed output in [-1, 1] mapped onto the box). ONNX and C are written from this one
description (:mod:`baselines.export.onnx`, :mod:`baselines.export.c_source`), and
:meth:`PolicyNetwork.forward` evaluates it in numpy; the tests check all three against SB3's
own ``predict``. Anything the walk does not know (another features extractor, a shared
network, an activation without a port) is refused with a ``ValueError`` naming it, rather
than exported wrong.
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3 import PPO, SAC, TD3
from stable_baselines3.common.distributions import (
    DiagGaussianDistribution,
    StateDependentNoiseDistribution,
)
from stable_baselines3.common.torch_layers import FlattenExtractor
from torch import nn

__all__ = ["ACTIVATIONS", "Dense", "PolicyNetwork", "policy_network"]

#: activations with an ONNX operator and a C port: torch module -> name
ACTIVATIONS: dict[type[nn.Module], str] = {
    nn.Tanh: "tanh",
    nn.ReLU: "relu",
    nn.Identity: "identity",
    nn.Hardtanh: "hardtanh",
}


@dataclasses.dataclass(frozen=True)
class Dense:
    """One layer y = act(W x + b): ``weight`` (out, in) and ``bias`` (out,), float32;
    ``activation`` a name of :data:`ACTIVATIONS`; ``limits`` (lo, hi) for ``"hardtanh"``."""

    weight: np.ndarray
    bias: np.ndarray
    activation: str = "identity"
    limits: tuple[float, float] | None = None

    @property
    def sizes(self) -> tuple[int, int]:
        """(inputs, outputs)."""
        return self.weight.shape[1], self.weight.shape[0]


def _activate(x: np.ndarray, layer: Dense) -> np.ndarray:
    if layer.activation == "tanh":
        return np.tanh(x)
    if layer.activation == "relu":
        return np.maximum(x, np.float32(0.0))
    if layer.activation == "hardtanh":
        lo, hi = layer.limits
        return np.clip(x, np.float32(lo), np.float32(hi))
    return x


@dataclasses.dataclass(frozen=True)
class PolicyNetwork:
    """The deterministic action of an SB3 policy from its (encoded) observation.

    Attributes:
        layers: the dense layers, input first.
        output: ``"clip"`` (the action clipped to [low, high], SB3 without squashing) or
            ``"unscale"`` (low + (a + 1) (high - low) / 2 of a squashed a in [-1, 1]).
        low, high: the action box, float32 (action_size,).
        algorithm: "PPO", "SAC" or "TD3".
    """

    layers: tuple[Dense, ...]
    output: str
    low: np.ndarray
    high: np.ndarray
    algorithm: str

    @property
    def input_size(self) -> int:
        return self.layers[0].sizes[0]

    @property
    def output_size(self) -> int:
        return self.layers[-1].sizes[1]

    @property
    def parameters(self) -> int:
        """Number of weights and biases."""
        return sum(x.weight.size + x.bias.size for x in self.layers)

    def describe(self) -> dict[str, Any]:
        """The architecture as JSON: sizes, activations, output transform."""
        return {
            "algorithm": self.algorithm,
            "layers": [
                {"inputs": x.sizes[0], "outputs": x.sizes[1], "activation": x.activation}
                | ({"limits": list(x.limits)} if x.limits else {})
                for x in self.layers
            ],
            "output": self.output,
            "action_low": self.low.tolist(),
            "action_high": self.high.tolist(),
            "parameters": self.parameters,
        }

    def forward(self, features: np.ndarray) -> np.ndarray:
        """Actions (n, action_size) float32 of encoded observations (n, input_size)."""
        h = np.asarray(features, dtype=np.float32).reshape(-1, self.input_size)
        for layer in self.layers:
            h = _activate(h @ layer.weight.T + layer.bias, layer)
        if self.output == "unscale":
            return self.low + (np.float32(0.5) * (h + np.float32(1.0)) * (self.high - self.low))
        return np.clip(h, self.low, self.high)


def _dense_layers(modules: list[nn.Module], where: str) -> list[Dense]:
    """Linear modules, each followed by at most one activation, as :class:`Dense` layers."""
    layers: list[Dense] = []
    for i, m in enumerate(modules):
        if isinstance(m, nn.Linear):
            w = m.weight.detach().cpu().numpy().astype(np.float32)
            b = np.zeros(w.shape[0], np.float32) if m.bias is None else m.bias.detach().cpu()
            layers.append(Dense(w, np.asarray(b, dtype=np.float32)))
            continue
        name = ACTIVATIONS.get(type(m))
        if name is None:
            raise ValueError(
                f"{where}[{i}] is a {type(m).__name__}: the exporter ports Linear layers and "
                f"the activations {', '.join(t.__name__ for t in ACTIVATIONS)}"
            )
        if name == "identity":
            continue
        if not layers or layers[-1].activation != "identity":
            raise ValueError(f"{where}[{i}] ({type(m).__name__}) does not follow a Linear layer")
        limits = (float(m.min_val), float(m.max_val)) if name == "hardtanh" else None
        layers[-1] = dataclasses.replace(layers[-1], activation=name, limits=limits)
    return layers


def _flat(module: nn.Module) -> list[nn.Module]:
    """The leaf modules of nested Sequentials, in order."""
    if isinstance(module, nn.Sequential):
        return [leaf for m in module for leaf in _flat(m)]
    return [module]


def _squash(layers: list[Dense], where: str) -> list[Dense]:
    """The last layer followed by tanh (a squashed Gaussian's mode is tanh of its mean)."""
    last = layers[-1]
    if last.activation == "identity":
        return [*layers[:-1], dataclasses.replace(last, activation="tanh")]
    if last.activation == "hardtanh":  # SAC's clip_mean: tanh(clip(mean)) needs two steps
        raise ValueError(f"{where}: a clipped mean (SAC clip_mean with use_sde) is not exported")
    raise ValueError(f"{where}: the mean ends in {last.activation}; expected a Linear layer")


def _check_extractor(extractor: nn.Module, where: str) -> None:
    if not isinstance(extractor, FlattenExtractor):
        raise ValueError(
            f"{where} is a {type(extractor).__name__}: only the FlattenExtractor of a flat Box "
            "observation is exported"
        )


def _ppo_layers(policy: Any) -> list[Dense]:
    _check_extractor(policy.pi_features_extractor, "policy.pi_features_extractor")
    dist = policy.action_dist
    if not isinstance(dist, (DiagGaussianDistribution, StateDependentNoiseDistribution)):
        raise ValueError(
            f"the policy's action distribution is a {type(dist).__name__}: only Gaussian "
            "(Box) actions are exported"
        )
    modules = [*_flat(policy.mlp_extractor.policy_net), *_flat(policy.action_net)]
    layers = _dense_layers(modules, "policy_net + action_net")
    if isinstance(dist, StateDependentNoiseDistribution) and dist.bijector is not None:
        layers = _squash(layers, "action_net")
    return layers


def _sac_layers(actor: Any) -> list[Dense]:
    _check_extractor(actor.features_extractor, "actor.features_extractor")
    modules = [*_flat(actor.latent_pi), *_flat(actor.mu)]
    return _squash(_dense_layers(modules, "actor.latent_pi + actor.mu"), "actor.mu")


def _td3_layers(actor: Any) -> list[Dense]:
    _check_extractor(actor.features_extractor, "actor.features_extractor")
    return _dense_layers(_flat(actor.mu), "actor.mu")


def policy_network(model: Any) -> PolicyNetwork:
    """The :class:`PolicyNetwork` of a loaded PPO, SAC or TD3 ``model`` with a flat Box
    observation and a Box action; ``TypeError``/``ValueError`` naming what is not exported."""
    obs_space, act_space = model.observation_space, model.action_space
    if not isinstance(obs_space, spaces.Box) or len(obs_space.shape) != 1:
        raise ValueError(f"observation space {obs_space}: only a flat Box is exported")
    if not isinstance(act_space, spaces.Box) or len(act_space.shape) != 1:
        raise ValueError(f"action space {act_space}: only a flat Box is exported")
    if isinstance(model, PPO):
        algo, layers = "PPO", _ppo_layers(model.policy)
    elif isinstance(model, SAC):
        algo, layers = "SAC", _sac_layers(model.policy.actor)
    elif isinstance(model, TD3):
        algo, layers = "TD3", _td3_layers(model.policy.actor)
    else:
        raise TypeError(f"model {type(model).__name__} is invalid: must be PPO, SAC or TD3")
    if not layers:
        raise ValueError("the policy has no Linear layer")
    for a, b in itertools.pairwise(layers):
        if a.sizes[1] != b.sizes[0]:
            raise ValueError(f"layer sizes do not chain: {a.sizes} then {b.sizes}")
    sizes = (layers[0].sizes[0], layers[-1].sizes[1])
    if sizes != (obs_space.shape[0], act_space.shape[0]):
        raise ValueError(f"the layers map {sizes[0]} -> {sizes[1]}, the spaces {obs_space}, "
                         f"{act_space}")  # fmt: skip
    for i, x in enumerate(layers):
        if not (np.isfinite(x.weight).all() and np.isfinite(x.bias).all()):
            raise ValueError(f"layer {i} holds NaN or inf weights")
    output = "unscale" if model.policy.squash_output else "clip"
    low = np.asarray(act_space.low, np.float32)
    high = np.asarray(act_space.high, np.float32)
    if not (np.isfinite(low).all() and np.isfinite(high).all()):
        raise ValueError(f"action space {act_space}: the box must be finite")
    return PolicyNetwork(tuple(layers), output, low, high, algo)
