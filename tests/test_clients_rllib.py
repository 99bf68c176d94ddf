"""RLlib PPO with one module shared by every paired UAV, on the PettingZoo parallel env.

RLlib pins its own Gymnasium version, so CI runs this file in a separate environment
(``.venv-rllib``, see ``.ci/run``, which sets ``PAIRFLOCK_REQUIRE_RLLIB=1`` so that a broken
install fails instead of skipping); the main suite skips it when RLlib cannot be imported.
"""

from __future__ import annotations

import math
import os

import pytest

try:  # RLlib may be installed without its pinned dependencies in the main environment
    import ray.rllib  # noqa: F401
except Exception as e:  # pragma: no cover - depends on the install
    if os.environ.get("PAIRFLOCK_REQUIRE_RLLIB") == "1":
        raise
    pytest.skip(f"RLlib is not usable here ({type(e).__name__}: {e})", allow_module_level=True)

from clients_docs import run_example

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_rllib_ppo_example_trains_one_shared_module():
    ns = run_example("RLlib")
    result = ns["result"]
    assert result["env_runners"]["num_env_steps_sampled_lifetime"] >= 64
    assert set(result["learners"]) - {"__all_modules__"} == {"shared"}  # one shared module
    ret = result["env_runners"].get("episode_return_mean")
    assert ret is None or math.isfinite(ret)
