"""Text specifications of the benchmark: policies with gains, and scenarios (config overrides).

Policy specs (one string each, so that a shell command names everything it compares)::

    smc                        the registered controller with its default gains
    smc:k=200,boundary_layer=0.5
    proportional:k_p=2
    sb3:runs/ppo/model.zip     a registered *prefix* ("sb3:"): the rest is its argument, a path

The text before the first colon picks the entry of ``baselines.POLICIES``: a plain name takes
``key=value`` gains after the colon, a prefix entry (registered with a trailing colon) takes
the rest verbatim, so a path may contain ``=`` or ``,`` without ambiguity.

Scenario specs are configuration overrides ``key=value[,key=value...]``, optionally labelled
``LABEL:key=value,...``. Values are read by :func:`parse_value`, the one value parser of every
CLI: numbers as written (``1e-3``, ``20``), ``true``/``none``, lists (``[[0, 1], [2, 3]]``),
else plain text (``dynamics=particle``).
"""

from __future__ import annotations

import ast
import dataclasses
import itertools
import json
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from baselines.controllers import POLICIES, make_pair_policy
from baselines.runtime import optional

__all__ = [
    "SHORT_NAMES",
    "PolicySpec",
    "Scenario",
    "expand_scenarios",
    "parse_assignment",
    "parse_assignments",
    "parse_policy",
    "parse_scenario",
    "parse_value",
    "scenario_label",
    "slug",
]

#: short names of config fields in scenario labels and table headers
SHORT_NAMES = {
    "n_uavs": "N",
    "pairs": "pairs",
    "obs_noise_position": "noise y (m)",
    "obs_noise_velocity": "noise y' (m/s)",
    "partner_delay": "delay (steps)",
    "disturbance_std": "disturbance (m/s^2)",
    "safety_filter": "filter",
}


@dataclasses.dataclass(frozen=True)
class PolicySpec:
    """A parsed policy spec: ``label`` (the text as given), the registry ``name`` passed to
    ``make_pair_policy`` (``"smc"`` or ``"sb3:/abs/path"``) and its keyword ``gains``."""

    label: str
    name: str
    gains: tuple[tuple[str, Any], ...] = ()

    @property
    def base(self) -> str:
        """The registry entry: ``"smc"``, ``"proportional"``, ``"sb3"``, ..."""
        return self.name.split(":", 1)[0]

    def build(self, env: Any) -> Any:
        return make_pair_policy(self.name, env, **dict(self.gains))


#: words that mean None, True and False
_WORDS: dict[str, Any] = {
    "none": None,
    "None": None,
    "null": None,
    "~": None,
    "true": True,
    "True": True,
    "false": False,
    "False": False,
}


def _number(text: str) -> int | float | None:
    """``text`` as Python reads a number (``20``, ``1_000``, ``1e-3``, ``5e1``, ``.5``,
    ``inf``), or None."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return None


def _numbers_inside(value: Any) -> Any:
    """Numbers written as text inside a YAML flow value (YAML 1.1 reads ``1e-3`` as text)."""
    if isinstance(value, str):
        n = _number(value.strip())
        return value if n is None else n
    if isinstance(value, list):
        return [_numbers_inside(v) for v in value]
    if isinstance(value, dict):
        return {k: _numbers_inside(v) for k, v in value.items()}
    return value


def _yaml_flow(text: str) -> Any:
    try:
        yaml = optional.load("yaml")
    except ModuleNotFoundError:  # the base install has no YAML: JSON and Python literals only
        raise ValueError(text) from None
    try:
        return _numbers_inside(yaml.safe_load(text))
    except yaml.YAMLError as e:
        raise ValueError(str(e)) from None


def parse_value(text: str) -> Any:
    """A command-line value as the user wrote it; the one parser of every CLI's ``KEY=VALUE``.

    * numbers as Python reads them: ``20`` (int), ``1e-3``, ``5e1``, ``0.5``, ``.5``, ``inf``
      (float), ``1_000``;
    * ``true``/``false``/``none`` (also ``True``, ``False``, ``None``, ``null``);
    * lists and mappings as JSON, Python literals or YAML flow (``[64, 64]``,
      ``[[0, 1], [2, 3]]``, ``{"net_arch": [64]}``, ``{net_arch: [64, 64]}``);
    * anything else is the text itself (``particle``, ``lin_3e-4``, ``auto``).
    """
    t = text.strip()
    if t in _WORDS:
        return _WORDS[t]
    number = _number(t)
    if number is not None:
        return number
    if t[:1] in "[{(":
        for parse in (json.loads, ast.literal_eval, _yaml_flow):
            try:
                return parse(t)
            except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
                continue
    return t


def parse_assignment(text: str, flag: str) -> tuple[str, Any]:
    """``"key=value"`` -> ``(key, parse_value(value))``; ``flag`` names the option in errors."""
    if not isinstance(text, str) or "=" not in text:
        raise ValueError(f"{flag} {text!r} is invalid: expected key=value")
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key:
        raise ValueError(f"{flag} {text!r} is invalid: empty key")
    return key, parse_value(raw)


def split_top_level(text: str, sep: str = ",") -> list[str]:
    """Split at ``sep`` outside brackets and braces: ``"a=[1,2],b=3"`` -> ``["a=[1,2]", "b=3"]``."""
    out, depth, cur = [], 0, []
    for ch in text:
        if ch in "[({":
            depth += 1
        elif ch in "])}":
            depth -= 1
        if ch == sep and depth == 0:
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur))
    return out


def parse_assignments(text: str, what: str) -> dict[str, Any]:
    """``"k=200,boundary_layer=0.5"`` -> ``{"k": 200, "boundary_layer": 0.5}``."""
    out: dict[str, Any] = {}
    if not text.strip():
        return out
    for item in split_top_level(text):
        key, eq, value = item.partition("=")
        key = key.strip()
        if not eq or not key or not value.strip():
            raise ValueError(f"{what}: {item!r} is invalid: expected key=value")
        if key in out:
            raise ValueError(f"{what}: {key!r} is given twice")
        out[key] = parse_value(value)
    return out


def parse_policy(spec: str) -> PolicySpec:
    """Parse one policy spec (module docstring); unknown names raise ``ValueError`` listing
    the registered ones. Prefix arguments that name an existing local file are made absolute
    so that worker processes started elsewhere find it."""
    if not isinstance(spec, str) or not spec.strip():
        raise ValueError(f"policy spec {spec!r} is invalid: expected e.g. 'smc' or 'smc:k=200'")
    spec = spec.strip()
    head, colon, rest = spec.partition(":")
    prefixes = sorted(k for k in POLICIES if k.endswith(":"))
    names = sorted(k for k in POLICIES if not k.endswith(":"))
    valid = ", ".join(names + [f"{p}<arg>" for p in prefixes])
    if colon and head + ":" in POLICIES:
        if not rest:
            raise ValueError(f"policy spec {spec!r} is invalid: {head}: needs an argument")
        arg = rest
        if Path(arg).exists() or Path(arg + ".zip").exists():
            arg = str(Path(arg).resolve())
        return PolicySpec(label=spec, name=f"{head}:{arg}")
    if head not in POLICIES:
        hint = ""
        if colon and head == "sb3":
            hint = (
                " (learned policies, 'sb3:<path>', need the SB3 support of "
                "pairflock-env[train]; it is not available in this install)"
            )
        raise ValueError(
            f"policy spec {spec!r} is invalid: unknown policy {head!r}{hint}; valid: {valid}"
        )
    gains = parse_assignments(rest, f"gains of policy {spec!r}")
    return PolicySpec(label=spec, name=head, gains=tuple(gains.items()))


@dataclasses.dataclass(frozen=True)
class Scenario:
    """One task of the grid: a label and the config overrides on top of the preset."""

    label: str
    overrides: tuple[tuple[str, Any], ...]

    @property
    def override_dict(self) -> dict[str, Any]:
        return dict(self.overrides)


def parse_scenario(text: str) -> tuple[str | None, dict[str, Any]]:
    """``"LABEL:key=v,key=v"`` or ``"key=v,..."`` -> (label or None, overrides)."""
    head, colon, rest = text.partition(":")
    if colon and "=" not in head:
        label = head.strip()
        if not label:
            raise ValueError(f"--scenario {text!r} is invalid: empty label before ':'")
        return label, parse_assignments(rest, f"--scenario {text!r}")
    return None, parse_assignments(text, f"--scenario {text!r}")


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (list, tuple)):
        return json.dumps(v, separators=(",", ":"))
    return str(v)


def _label_value(key: str, v: Any) -> str:
    if key == "pairs" and isinstance(v, (list, tuple)):
        canonical = [[2 * i, 2 * i + 1] for i in range(len(v))]
        if [list(p) for p in v] == canonical:
            return str(len(v))  # K pairs (0, 1), (2, 3), ...: the --pairs K shortcut
    return _fmt(v)


def scenario_label(overrides: Mapping[str, Any]) -> str:
    """``{"n_uavs": 50, "partner_delay": 5}`` -> ``"N=50, partner_delay=5"``; the pairs
    ``(0, 1), (2, 3)`` are labelled ``pairs=2``."""
    if not overrides:
        return "nominal"
    return ", ".join(
        f"{'N' if k == 'n_uavs' else k}={_label_value(k, v)}" for k, v in overrides.items()
    )


def expand_scenarios(
    base: Mapping[str, Any],
    listed: Sequence[tuple[str | None, Mapping[str, Any]]],
    grid: Mapping[str, Sequence[Any]],
) -> list[Scenario]:
    """Every listed scenario (default: one with no overrides) times the grid product.

    ``base`` overrides apply to all; a key may not be both listed and a grid axis. Labels:
    the listed label (or its overrides) joined with the grid values, e.g. ``"delay 5, N=50"``.
    """
    listed = list(listed) or [(None, {})]
    axes = [(k, list(v)) for k, v in grid.items()]
    for k, vals in axes:
        if not vals:
            raise ValueError(f"grid axis {k!r} has no values")
        if len(set(map(_fmt, vals))) != len(vals):
            raise ValueError(f"grid axis {k!r} repeats a value: {vals}")
    out: list[Scenario] = []
    for label, ov in listed:
        clash = sorted(set(ov) & {k for k, _ in axes})
        if clash:
            raise ValueError(
                f"scenario {label or scenario_label(ov)!r} sets {clash}, which is also a grid "
                "axis (--set or a shortcut option); set it once"
            )
        for combo in itertools.product(*(vals for _, vals in axes)):
            g = {k: v for (k, _), v in zip(axes, combo, strict=False)}
            varied = {k: v for (k, vals), v in zip(axes, combo, strict=False) if len(vals) > 1}
            parts = [label if label is not None else (scenario_label(ov) if ov else "")]
            if varied:
                parts.append(scenario_label(varied))
            text = ", ".join(p for p in parts if p) or "nominal"
            out.append(Scenario(text, tuple({**base, **ov, **g}.items())))
    labels = [s.label for s in out]
    dup = sorted({x for x in labels if labels.count(x) > 1})
    if dup:
        raise ValueError(f"scenario labels repeat: {dup}; give distinct LABEL: prefixes")
    return out


def slug(text: str) -> str:
    """File-name-safe form of a label.

    ``"N=50"`` -> ``"n50"``, ``"smc:k=200"`` -> ``"smc-k200"``.
    """
    s = re.sub(r"[=\s]+", "", text.lower())
    s = re.sub(r"(?<!\d)\.|\.(?!\d)", "-", s)  # keep only decimal points
    s = re.sub(r"[^a-z0-9.]+", "-", s).strip("-")
    return s or "x"
