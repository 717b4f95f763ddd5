"""hgym's multi-agent flows as PettingZoo ``ParallelEnv`` (the channel flows: one agent per wall
actuator patch).

    from hgym.pettingzoo import parallel_env

    env = parallel_env("TCFMini_3D_Retau180", level="coarse")
    observations, infos = env.reset(seed=0)
    while env.agents:
        actions = {agent: env.action_space(agent).sample() for agent in env.agents}
        observations, rewards, terminations, truncations, infos = env.step(actions)

The agents are those ``hgym train`` trains (the Rust environment's own decomposition): each sees
its local observation (the global observation's indices listed by ``agent_layout``) and sets its
own actuators; the reward is the environment's (``"global"``) or each agent's own (``"local"``),
as the spec says. Every agent acts at every step and all episodes end together.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from hgym import _hgym
from hgym.env import _overrides


def parallel_env(env_id: str, level: str = "coarse", render_mode: str | None = None, **overrides: Any) -> "HgymParallelEnv":
    """The multi-agent view of ``env_id`` (``overrides``: spec fields, as for ``gym.make``)."""
    return HgymParallelEnv(env_id, level=level, render_mode=render_mode, **overrides)


class HgymParallelEnv(ParallelEnv):
    """One hgym flow split into its agents, all acting at once (PettingZoo's parallel API)."""

    metadata = {"name": "hgym_parallel_v0", "render_modes": ["rgb_array"], "is_parallelizable": True}

    def __init__(self, env_id: str, level: str = "coarse", render_mode: str | None = None, **overrides: Any):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not one of {self.metadata['render_modes']} (or None)")
        self._env = _hgym.Env(env_id, level, _overrides(overrides))
        layout = self._env.agents()
        if layout is None:
            raise ValueError(f"{env_id} declares no agents; use gymnasium.make('hgym/{env_id}-v0') (the channel flows have agents)")
        self.agent_layout = layout
        self._obs_idx = [np.asarray(o, dtype=np.intp) for o in layout["obs"]]
        self._act_idx = [np.asarray(a, dtype=np.intp) for a in layout["act"]]
        self._local = layout["reward"] == "local"
        self.possible_agents = [f"agent_{i}" for i in range(len(self._obs_idx))]
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self.agents: list[str] = []
        olow, ohigh = self._env.observation_bounds()
        alow, ahigh = self._env.action_bounds()
        self._act_dim = len(alow)
        self._observation_spaces = {
            a: spaces.Box(olow[idx], ohigh[idx], dtype=np.float32) for a, idx in zip(self.possible_agents, self._obs_idx)
        }
        self._action_spaces = {
            a: spaces.Box(alow[idx], ahigh[idx], dtype=np.float32) for a, idx in zip(self.possible_agents, self._act_idx)
        }
        self.render_mode = render_mode
        self.env_id = env_id
        self.level = level

    def observation_space(self, agent: str) -> spaces.Box:
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Box:
        return self._action_spaces[agent]

    def _split(self, obs: np.ndarray) -> dict:
        return {a: obs[idx] for a, idx in zip(self.possible_agents, self._obs_idx)}

    def reset(self, seed: int | None = None, options: dict | None = None):
        """Starts an episode of the shared flow (``seed`` as ``HgymEnv.reset``)."""
        if seed is None:
            seed = int(np.random.default_rng().integers(0, 2**63 - 1))
        if seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed}")
        obs, info = self._env.reset(int(seed))
        self.agents = list(self.possible_agents)
        return self._split(obs), {a: dict(info) for a in self.agents}

    def step(self, actions: dict):
        """Every live agent's action (finite, clipped to its box) for one control interval."""
        if not self.agents:
            raise RuntimeError("step called before reset (or after the episode ended): call reset first")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"no action for {len(missing)} agent(s), e.g. {missing[0]}: every agent acts at every step")
        a = np.zeros(self._act_dim, dtype=np.float64)
        for agent, act in actions.items():
            if agent not in self._index:
                raise ValueError(f"unknown agent {agent!r}; the agents are agent_0 .. agent_{len(self.possible_agents) - 1}")
            a[self._act_idx[self._index[agent]]] = np.asarray(act, dtype=np.float64).reshape(-1)
        obs, reward, terminated, truncated, info = self._env.step(a)
        local = self._env.agent_rewards() if self._local else None
        rewards = {ag: float(local[i] if local is not None else reward) for i, ag in enumerate(self.possible_agents)}
        agents = self.agents
        if terminated or truncated:
            self.agents = []
        return (
            self._split(obs),
            rewards,
            {ag: bool(terminated) for ag in agents},
            {ag: bool(truncated) for ag in agents},
            {ag: dict(info) for ag in agents},
        )

    def render(self):
        """The flow's field as an RGB array (the channels' wall shear stress excess)."""
        if self.render_mode != "rgb_array":
            return None
        return self._env.render_rgb()

    def close(self):
        pass
