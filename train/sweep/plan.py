"""What a sweep is: the base settings, the settings grid (or search space) and the seeds.

A :class:`SweepPlan` expands into :class:`Trial` records, one per (setting, seed). A trial
holds the complete :class:`~train.settings.RunSettings` of its run (as a dict), so a worker
process, a Ray actor or a later resume rebuilds exactly the same run from it. Dotted keys map
onto the settings::

    env.n_uavs=50                  PairFlockConfig override (the ``env:`` section)
    eval_env.horizon=20            evaluation-only override (``eval_env:``)
    hp.learning_rate=1e-4          SB3 hyperparameter (``hyperparameters:``), nested with dots:
                                   hp.policy_kwargs.net_arch=[64,64]
    interface.w_band=0.5           learning-interface parameter (``interface_params:``; also
                                   ``interface_params.``)
    num_swarms=16, algo=sac, ...   a top-level RunSettings field

Every value is validated by :func:`train.settings.settings_from_sources`, the code path of
``python -m train``: a sweep accepts exactly the settings a single run accepts.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import itertools
import json
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from baselines.evaluation.specs import parse_assignment, split_top_level
from train.settings import settings_from_sources

__all__ = [
    "DOMAINS",
    "SWEEP_FILE",
    "SweepPlan",
    "Trial",
    "load_sweep",
    "parse_domain",
    "parse_grid",
    "parse_value",
    "same_plan",
    "setting_label",
    "setting_slug",
    "settings_for",
    "split_values",
]

#: the sweep's definition and trial list inside the sweep directory
SWEEP_FILE = "sweep.json"

#: dotted-key prefixes and the settings section each one addresses
_SECTIONS = {
    "env": "env",
    "eval_env": "eval_env",
    "hp": "hp",
    "hyperparameters": "hp",
    "interface": "interface",
    "interface_params": "interface",
}

#: search-space kinds of ``--grid KEY=KIND:LOW:HIGH`` (Optuna search only)
DOMAINS = ("uniform", "loguniform", "int")


def parse_value(key: str, raw: str, flag: str) -> Any:
    """One value as every CLI of the project parses it (numbers as written, lists, ...)."""
    return parse_assignment(f"{key}={raw}", flag)[1]


def split_values(text: str) -> list[str]:
    """``a,b,[1,2]`` -> ``["a", "b", "[1,2]"]``: commas inside brackets or braces stay."""
    return [part.strip() for part in split_top_level(text)]


def _split_key(text: str, flag: str) -> tuple[str, str]:
    if "=" not in text:
        raise ValueError(f"{flag} {text!r} is invalid: expected KEY=VALUE[,VALUE...]")
    key, raw = text.split("=", 1)
    key = key.strip()
    if not key or not raw.strip():
        raise ValueError(f"{flag} {text!r} is invalid: empty key or value")
    if key == "seed":
        raise ValueError(f"{flag} {text!r} is invalid: seeds are given with --seeds")
    return key, raw


def parse_grid(text: str, flag: str = "--grid") -> tuple[str, list[Any]]:
    """``hp.learning_rate=3e-4,1e-4`` -> ``("hp.learning_rate", [0.0003, 0.0001])``."""
    key, raw = _split_key(text, flag)
    raws = split_values(raw)
    if any(not v for v in raws):
        raise ValueError(f"{flag} {text!r} is invalid: an empty value in the list")
    return key, [parse_value(key, v, flag) for v in raws]


def parse_domain(text: str, flag: str = "--grid") -> tuple[str, dict[str, Any]]:
    """A search dimension: ``KEY=a,b,c`` (choice) or ``KEY=uniform|loguniform|int:LOW:HIGH``."""
    key, raw = _split_key(text, flag)
    kind, _, bounds = raw.partition(":")
    if kind in DOMAINS and bounds:
        try:
            lo, hi = (float(x) for x in bounds.split(":"))
        except ValueError:
            raise ValueError(
                f"{flag} {text!r} is invalid: write {kind}:LOW:HIGH with two numbers"
            ) from None
        if not lo < hi or (kind == "loguniform" and lo <= 0):
            raise ValueError(
                f"{flag} {text!r} is invalid: needs LOW < HIGH"
                + (" and LOW > 0" * (kind == "loguniform"))
            )
        if kind == "int":
            lo, hi = int(lo), int(hi)
        return key, {"kind": kind, "low": lo, "high": hi}
    return key, {"kind": "choice", "values": parse_grid(text, flag)[1]}


def settings_for(
    base: Mapping[str, Any],
    assignments: Sequence[tuple[str, Any]],
    flags: Mapping[str, Any] | None = None,
    where: str = "--grid",
):
    """Validated :class:`~train.settings.RunSettings`: ``base`` (a settings mapping, e.g. the
    ``--config`` YAML) with dotted ``assignments`` and ``flags`` on top."""
    data = copy.deepcopy(dict(base))
    env_sets, hp_sets, interface_sets = [], [], []
    for key, value in assignments:
        head, _, rest = key.partition(".")
        section = _SECTIONS.get(head) if rest else None
        if not rest:
            data[key] = value  # a top-level field; unknown names fail with a suggestion
        elif section == "env":
            env_sets.append((rest, value))
        elif section == "hp":
            hp_sets.append((rest, value))
        elif section == "interface":
            interface_sets.append((rest, value))
        elif section == "eval_env":
            data["eval_env"] = {**dict(data.get("eval_env") or {}), rest: value}
        else:
            raise ValueError(
                f"{where} key {key!r} is invalid: a dotted key starts with one of "
                f"{', '.join(sorted(_SECTIONS))} (or name a top-level settings field)"
            )
    return settings_from_sources(
        data, flags, env_sets=env_sets, hp_sets=hp_sets, interface_sets=interface_sets
    )


def _format(value: Any) -> str:
    if isinstance(value, float):
        return repr(value)  # shortest exact form: distinct values never share a directory
    if isinstance(value, str):
        return value
    return json.dumps(value, separators=(",", ":"))


def setting_label(assignments: Mapping[str, Any]) -> str:
    """``hp.learning_rate=0.0003 env.n_uavs=20`` (``default`` for no assignment)."""
    return " ".join(f"{k}={_format(v)}" for k, v in assignments.items()) or "default"


def setting_slug(assignments: Mapping[str, Any]) -> str:
    """A directory name for a setting: its label with unsafe characters replaced."""
    label = ",".join(f"{k}={_format(v)}" for k, v in assignments.items()) or "default"
    slug = re.sub(r"[^A-Za-z0-9._=,+-]", "_", label)
    if len(slug) > 80:
        digest = hashlib.sha256(label.encode()).hexdigest()[:10]
        slug = f"{slug[:60]}-{digest}"
    return slug


@dataclasses.dataclass(frozen=True)
class Trial:
    """One run of the sweep: a setting (dotted assignments) and a seed.

    ``settings`` is the full :meth:`RunSettings.to_dict`; ``run_dir`` is relative to the
    sweep directory, so a sweep directory can be moved and still resumed.
    """

    name: str
    setting: str
    label: str
    assignments: dict[str, Any]
    seed: int
    settings: dict[str, Any]
    run_dir: str

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict (what workers and Ray Tune receive)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Trial:
        """The inverse of :meth:`to_dict`."""
        return cls(**{f.name: d[f.name] for f in dataclasses.fields(cls)})

    @property
    def spec_hash(self) -> str:
        """Fingerprint of what the trial computes (a finished result is reused only if equal)."""
        blob = json.dumps(self.to_dict(), sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()[:16]


@dataclasses.dataclass
class SweepPlan:
    """The definition of a sweep (what ``sweep.json`` stores under ``plan``).

    ``base`` is the settings mapping of ``--config`` (or empty), ``fixed`` the ``--set``
    assignments applied to every trial, ``grid`` the ``--grid`` keys with their values (a
    grid sweep) or their search domains (``search == "optuna"``), ``seeds`` the training
    seeds. Every trial runs ``total_steps`` steps when given (else the config's).
    """

    base: dict[str, Any]
    fixed: list[tuple[str, Any]]
    grid: list[tuple[str, Any]]
    seeds: list[int]
    total_steps: int | None = None
    search: str | None = None
    samples: int = 0
    metric: str = "final_score"
    mode: str = "min"

    def __post_init__(self) -> None:
        self.fixed = [tuple(x) for x in self.fixed]
        self.grid = [tuple(x) for x in self.grid]
        keys = [k for k, _ in self.grid]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            raise ValueError(f"--grid key {dup[0]!r} is given twice: list all values in one")
        if not self.seeds or len(set(self.seeds)) != len(self.seeds):
            raise ValueError(f"--seeds {self.seeds!r} is invalid: distinct seeds, at least one")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> SweepPlan:
        """The inverse of :meth:`to_dict`."""
        return cls(**dict(d))

    def flags(self, seed: int) -> dict[str, Any]:
        """Settings that come from the sweep's own flags."""
        return {"seed": seed, "total_steps": self.total_steps}

    def make_trial(self, assignments: Mapping[str, Any], seed: int) -> Trial:
        """The trial of one setting (grid point or sampled configuration) and seed."""
        settings = settings_for(self.base, [*self.fixed, *assignments.items()], self.flags(seed))
        slug = setting_slug(assignments)
        return Trial(
            name=f"{slug}/seed_{seed}",
            setting=slug,
            label=setting_label(assignments),
            assignments=dict(assignments),
            seed=int(seed),
            settings=settings.to_dict(),
            run_dir=f"trials/{slug}/seed_{seed}",
        )

    def grid_points(self) -> list[dict[str, Any]]:
        """Every setting of a grid sweep, in the order of the ``--grid`` flags."""
        keys = [k for k, _ in self.grid]
        return [
            dict(zip(keys, vals, strict=True))
            for vals in itertools.product(*(v for _, v in self.grid))
        ]

    def trials(self) -> list[Trial]:
        """All trials of a grid sweep: settings x seeds (setting-major)."""
        if self.search is not None:
            raise ValueError("a search sweep draws its settings while it runs")
        return [self.make_trial(p, s) for p in self.grid_points() for s in self.seeds]

    def check_search_space(self) -> None:
        """Validate a search sweep up front: every choice and both ends of every range."""
        for key, dom in self.grid:
            values = dom["values"] if dom["kind"] == "choice" else [dom["low"], dom["high"]]
            for v in values:
                self.make_trial({key: v}, self.seeds[0])


def load_sweep(out: Path) -> dict[str, Any] | None:
    """The stored ``sweep.json`` of a sweep directory, or None."""
    path = Path(out) / SWEEP_FILE
    if not path.is_file():
        return None
    return json.loads(path.read_text(encoding="utf-8"))


def same_plan(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    """Whether two plan dicts describe the same sweep (compared as stored JSON)."""
    norm = lambda d: json.dumps(d, sort_keys=True, default=str)  # noqa: E731
    return norm(a) == norm(b)
