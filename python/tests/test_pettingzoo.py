"""The multi-agent flows through PettingZoo's parallel API: its own API test, and the agents'
observations, actions and rewards against the Rust environment stepped directly, bitwise."""

import numpy as np
import pytest

pytest.importorskip("pettingzoo")

import hgym  # noqa: E402,F401
from hgym import _hgym  # noqa: E402
from hgym.env import _overrides  # noqa: E402
from hgym.pettingzoo import parallel_env  # noqa: E402
from pettingzoo.test import parallel_api_test  # noqa: E402

# A short spin-up (the flow is still transitional: enough for the API) and short episodes.
SHORT = {"spin_up": 4.0, "episode_actions": 6}


def test_the_channel_passes_pettingzoos_parallel_api_test():
    env = parallel_env("TCFMini_3D_Retau180", **SHORT)
    assert len(env.possible_agents) == 128
    assert env.observation_space("agent_0").shape == (18,)
    assert env.action_space("agent_5").shape == (1,)
    parallel_api_test(env, num_cycles=10)


def test_agents_are_the_rust_environment_split_bitwise():
    env = parallel_env("TCFMini_3D_Retau180", **SHORT)
    direct = _hgym.Env("TCFMini_3D_Retau180", "coarse", _overrides(SHORT))
    obs, _ = env.reset(seed=3)
    whole, _ = direct.reset(3)
    for i, agent in enumerate(env.possible_agents):
        assert np.array_equal(obs[agent], whole[env.agent_layout["obs"][i]])
    rng = np.random.default_rng(0)
    for _ in range(3):
        actions = {a: rng.uniform(-1, 1, size=1).astype(np.float32) for a in env.agents}
        obs, rewards, _, truncations, _ = env.step(actions)
        a = np.zeros(128)
        for i, agent in enumerate(env.possible_agents):
            a[env.agent_layout["act"][i]] = actions[agent].astype(np.float64)
        whole, reward, _, truncated, _ = direct.step(a)
        assert all(np.array_equal(obs[ag], whole[env.agent_layout["obs"][i]]) for i, ag in enumerate(env.possible_agents))
        assert all(r == reward for r in rewards.values())
        assert all(t == truncated for t in truncations.values())


def test_a_flow_without_agents_is_refused_with_the_alternative():
    with pytest.raises(ValueError, match="declares no agents"):
        parallel_env("Cylinder_2D_Re100")
