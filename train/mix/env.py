"""One SB3 VecEnv over several tasks: the rows of several PairFlockSB3VecEnv, concatenated.

PPO (or SAC, TD3) sees one batch whose first rows are task 0's paired UAVs, the next task 1's,
and so on; every call is delegated to the task envs by row range, so each task keeps its own
batched core, config and per-swarm generators, and a row behaves exactly as the same row of
its task env alone (``tests/test_train_mix.py`` checks observations, rewards, dones, infos
and terminal observations row for row).

Seeds: task k draws from child k of ``SeedSequence(seed)`` and, inside the task env, swarm b
from that child's child b, so every swarm of every task has its own stream, derived from the
run seed and the task index alone (no global random state).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from pairflock_env.core import real_array
from pairflock_env.envs.sb3 import PairFlockSB3VecEnv
from pairflock_env.seeding import check_seed, spawn
from train.mix.tasks import training_tasks

__all__ = ["TaskMixVecEnv", "make_mix_vec_env", "task_seeds"]


def task_seeds(seed: Any, num_tasks: int) -> list[np.random.SeedSequence]:
    """The seed of each task: child k of ``SeedSequence(seed)`` (an int >= 0 or a
    SeedSequence, not advanced); ``None`` draws fresh OS entropy."""
    s = check_seed(seed, "seed")
    return spawn(np.random.SeedSequence() if s is None else s, num_tasks)


class TaskMixVecEnv(VecEnv):
    """SB3 ``VecEnv`` whose rows are those of ``envs`` (one VecEnv per task), in order.

    ``step``, ``reset``, ``seed``, ``set_options``, ``get_attr``, ``set_attr``,
    ``env_method``, ``env_is_wrapped``, ``get_images``, ``get_state`` and ``set_state``
    delegate to the task envs by row range (:attr:`row_slices`). All task envs must have the
    same observation and action spaces (one network serves every row); ``names`` label the
    tasks (default ``task0``, ``task1``, ...).
    """

    def __init__(self, envs: Sequence[VecEnv], names: Sequence[str] | None = None) -> None:
        envs = list(envs)
        if not envs or not all(isinstance(e, VecEnv) for e in envs):
            raise TypeError(f"envs={envs!r} is invalid: must be a non-empty list of SB3 VecEnvs")
        names = [f"task{k}" for k in range(len(envs))] if names is None else list(names)
        if len(names) != len(envs) or len(set(names)) != len(names):
            raise ValueError(f"names={names!r} is invalid: one distinct name per env")
        first = envs[0]
        for k, e in enumerate(envs[1:], 1):
            for what in ("observation_space", "action_space"):
                if getattr(e, what) != getattr(first, what):
                    raise ValueError(
                        f"envs[{k}] ({names[k]}) has {what} {getattr(e, what)}, envs[0] has "
                        f"{getattr(first, what)}: every task must give the same spaces"
                    )
        self.envs, self.task_names = envs, names
        bounds = np.cumsum([0] + [e.num_envs for e in envs])
        #: the rows of each task: ``rows[row_slices[k]]`` are task k's
        self.row_slices = [slice(int(a), int(b)) for a, b in itertools.pairwise(bounds)]
        self._task_of_row = np.repeat(np.arange(len(envs)), np.diff(bounds))
        self._actions: np.ndarray | None = None
        super().__init__(int(bounds[-1]), first.observation_space, first.action_space)

    # ------------------------------------------------------------------ description
    @property
    def num_tasks(self) -> int:
        return len(self.envs)

    @property
    def interface(self) -> Any:
        """The learning interface (the same for every task; task 0's object)."""
        return self.envs[0].interface

    @property
    def num_swarms(self) -> int:
        """Swarms of all tasks together."""
        return sum(int(getattr(e, "num_swarms", e.num_envs)) for e in self.envs)

    def task_of_row(self, row: int) -> int:
        """The index of the task row ``row`` belongs to."""
        return self._locate([row])[0][0]

    # ------------------------------------------------------------------ seeding/reset
    def seed(self, seed: Any = None) -> Sequence[Any]:
        """Seeds for the next ``reset()``: task k gets child k of ``SeedSequence(seed)``
        (see :func:`task_seeds`); a list of one seed per swarm (all tasks' swarms in order)
        is split among the tasks. Returns one seed per row."""
        if isinstance(seed, Sequence) and not isinstance(seed, (str, bytes)):
            counts = [int(getattr(e, "num_swarms", e.num_envs)) for e in self.envs]
            if len(seed) != sum(counts):
                raise ValueError(f"seed has {len(seed)} entries, expected {sum(counts)} (swarms)")
            edges = np.cumsum([0, *counts])
            parts = [list(seed[a:b]) for a, b in itertools.pairwise(edges)]
        else:
            parts = task_seeds(seed, self.num_tasks)
        return [s for seeds in self._apply_to_tasks("seed", parts) for s in seeds]

    def set_options(self, options: dict | list[dict | None] | None = None) -> None:
        """Options for the next ``reset()``: one dict for every row or a list of ``num_envs``,
        split among the tasks (each task env checks its part)."""
        if isinstance(options, list):
            if len(options) != self.num_envs:
                raise ValueError(
                    f"options has {len(options)} entries, expected {self.num_envs} (rows)"
                )
            parts = [options[s] for s in self.row_slices]
        else:
            parts = [options] * self.num_tasks
        self._apply_to_tasks("set_options", parts)

    def _apply_to_tasks(self, method: str, parts: Sequence[Any]) -> list[Any]:
        """``env.<method>(part)`` on every task env, all or nothing: a task env that rejects
        its part raises naming the task and its rows, and the pending seeds and options of
        the task envs before it are put back (SB3 VecEnvs keep them in ``_seeds`` and
        ``_options``)."""
        pending = [(list(e._seeds), list(e._options)) for e in self.envs]
        out = []
        for k, (env, part) in enumerate(zip(self.envs, parts, strict=True)):
            try:
                out.append(getattr(env, method)(part))
            except (TypeError, ValueError) as err:
                for e, (seeds, options) in zip(self.envs, pending, strict=True):
                    e._seeds, e._options = seeds, options
                rows = self.row_slices[k]
                where = f"task {k} ({self.task_names[k]}, rows {rows.start}-{rows.stop - 1})"
                raise type(err)(f"{where}: {err}") from err
        return out

    def reset(self) -> np.ndarray:
        """Reset every task env (with its pending seeds and options); the rows' observations."""
        obs = [env.reset() for env in self.envs]
        self.reset_infos = [i for env in self.envs for i in env.reset_infos]
        return np.concatenate(obs)

    # ------------------------------------------------------------------ step
    def step_async(self, actions: np.ndarray) -> None:
        """Hand each task env its rows of ``actions`` (num_envs, dim)."""
        # every row is checked before any task env takes its part: a bad action leaves all
        # task envs without a pending step
        actions = real_array(actions, "actions", (self.num_envs, *self.action_space.shape))
        if not np.isfinite(actions).all():  # finite, but beyond float64 (np.longdouble)
            raise ValueError("actions are beyond float64's range")
        for env, s in zip(self.envs, self.row_slices, strict=True):
            env.step_async(actions[s])

    def step_wait(self):
        """Every task env's step, rows concatenated (each auto-resets its ended swarms)."""
        results = [env.step_wait() for env in self.envs]
        obs = np.concatenate([r[0] for r in results])
        rewards = np.concatenate([r[1] for r in results])
        dones = np.concatenate([r[2] for r in results])
        infos = [i for r in results for i in r[3]]
        for env, s in zip(self.envs, self.row_slices, strict=True):
            self.reset_infos[s] = env.reset_infos
        return obs, rewards, dones, infos

    # ------------------------------------------------------------------ state
    def get_state(self) -> dict[str, Any]:
        """Every task env's :meth:`get_state`, in task order."""
        return {"tasks": [env.get_state() for env in self.envs], "names": list(self.task_names)}

    def set_state(self, state: Mapping[str, Any]) -> None:
        """Restore a :meth:`get_state` snapshot; every task's part is checked before any is
        restored, so a mismatch leaves the env unchanged."""
        if not isinstance(state, Mapping) or not isinstance(state.get("tasks"), list):
            raise TypeError("state must be a dict returned by TaskMixVecEnv.get_state()")
        parts = state["tasks"]
        if list(state.get("names", [])) != self.task_names or len(parts) != self.num_tasks:
            raise ValueError(
                f"state holds tasks {state.get('names')}, this env has {self.task_names}"
            )
        for k, (env, part) in enumerate(zip(self.envs, parts, strict=True)):
            if part.get("config") != env.config.to_dict():
                raise ValueError(f"state of task {k} ({self.task_names[k]}) has another config")
            if part["core"].num_swarms != env.num_swarms:
                raise ValueError(f"state of task {k} ({self.task_names[k]}) has another size")
        for env, part in zip(self.envs, parts, strict=True):
            env.set_state(part)

    # ------------------------------------------------------------------ attributes
    def _locate(self, indices: Any) -> list[tuple[int, int]]:
        """(task, row within the task) of each global row index."""
        n = self.num_envs
        if indices is None:
            idx: Iterable[int] = range(n)
        elif isinstance(indices, (int, np.integer)):
            idx = [int(indices)]
        else:
            idx = [int(i) for i in indices]
        out = []
        for i in idx:
            if not -n <= i < n:
                raise IndexError(f"indices={indices!r} is invalid: rows are 0..{n - 1}")
            i %= n
            k = int(self._task_of_row[i])
            out.append((k, i - self.row_slices[k].start))
        return out

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        return [self.envs[k].get_attr(attr_name, [i])[0] for k, i in self._locate(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        for k, i in self._locate(indices):
            self.envs[k].set_attr(attr_name, value, [i])

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list:
        return [
            self.envs[k].env_method(method_name, *method_args, indices=[i], **method_kwargs)[0]
            for k, i in self._locate(indices)
        ]

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [
            self.envs[k].env_is_wrapped(wrapper_class, [i])[0] for k, i in self._locate(indices)
        ]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [img for env in self.envs for img in env.get_images()]

    def close(self) -> None:
        for env in self.envs:
            env.close()


def make_mix_vec_env(settings: Any, seed_offset: int = 0) -> TaskMixVecEnv:
    """The training VecEnv of a run with ``tasks``: one PairFlockSB3VecEnv per task (its
    swarms, its config), seeded by :func:`task_seeds` from the run seed."""
    tasks = training_tasks(settings)
    seeds = task_seeds(np.random.SeedSequence([settings.seed, seed_offset]), len(tasks))
    envs = [
        PairFlockSB3VecEnv(
            settings.preset,
            num_swarms=t.num_swarms,
            seed=s,
            **settings.env_kwargs(),
            **t.overrides,
        )
        for t, s in zip(tasks, seeds, strict=True)
    ]
    return TaskMixVecEnv(envs, [t.name for t in tasks])
