"""The Gymnasium classes around the Rust environments (``hgym._hgym``)."""

from __future__ import annotations

import json
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

from hgym import _hgym

_LEVELS = ("coarse", "default", "fine")


def envs() -> list[dict]:
    """Every hgym ID with its spec's facts (family, solver, dimension, Reynolds number,
    observation and action sizes, control interval, differentiable, spec hash, spec as TOML)."""
    return _hgym.envs()


def _overrides(kwargs: dict) -> str | None:
    return json.dumps(kwargs) if kwargs else None


def _seed(rng: np.random.Generator) -> int:
    return int(rng.integers(0, 2**63 - 1))


class HgymEnv(gymnasium.Env):
    """One hgym flow environment with Gymnasium 1.x semantics.

    ``HgymEnv(env_id, level="coarse", render_mode=None, **overrides)``: ``overrides`` are spec
    fields (``hgym envs show ID`` lists them), checked as the CLI checks ``[env]``.
    Observations and actions are float32 ``Box`` spaces; ``info`` has the Rust info's keys
    (time, forces, actuation, and a ``diverged`` reason when the solver blew up, which ends the
    episode with ``terminated=True``). ``render()`` returns the vorticity as an RGB array.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, env_id: str, level: str = "coarse", render_mode: str | None = None, **overrides: Any):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not one of {self.metadata['render_modes']} (or None)")
        self._env = _hgym.Env(env_id, level, _overrides(overrides))
        self.render_mode = render_mode
        low, high = self._env.observation_bounds()
        self.observation_space = spaces.Box(low, high, dtype=np.float32)
        low, high = self._env.action_bounds()
        self.action_space = spaces.Box(low, high, dtype=np.float32)
        self.env_id = env_id
        self.level = level

    @property
    def spec_toml(self) -> str:
        """The spec this environment runs (overrides applied), as ``hgym envs show`` prints it."""
        return self._env.spec_toml

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Starts an episode. ``seed`` seeds the flow's perturbation; without one, a seed is drawn
        from the environment's generator (itself seeded by the first ``reset(seed=...)``)."""
        super().reset(seed=seed)
        if seed is None:
            seed = _seed(self.np_random)
        if seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed}")
        return self._env.reset(int(seed))

    def step(self, action):
        """Applies ``action`` (finite, clipped to the box) for one control interval."""
        try:  # a flat float32 or float64 array goes to Rust as it is
            return self._env.step(action)
        except TypeError:
            return self._env.step(np.ascontiguousarray(action, dtype=np.float64).reshape(-1))

    def render(self):
        """The vorticity as an ``(height, width, 3)`` uint8 array (bodies grey), in
        ``render_mode="rgb_array"``; ``None`` otherwise."""
        if self.render_mode != "rgb_array":
            return None
        return self._env.render_rgb()

    def reward_action_gradients(self, k: int) -> np.ndarray:
        """For the last ``k`` steps, d(sum of their rewards)/d(each step's action), ``(k, act_dim)``
        (differentiable flows: the Kolmogorov family)."""
        return self._env.reward_action_gradients(k)


def make_vec(env_id: str, n: int, level: str = "coarse", **overrides: Any) -> "HgymVectorEnv":
    """``n`` instances of ``env_id`` stepped together on Rust threads."""
    return HgymVectorEnv(env_id, n, level=level, **overrides)


class HgymVectorEnv(gymnasium.vector.VectorEnv):
    """``n`` hgym environments stepped in one call on Rust threads, bitwise the same as ``n``
    separate ``HgymEnv`` with the same seeds. An instance whose episode ends is reset on the
    next ``step`` (Gymnasium's default next-step autoreset); its ``step`` returns the reset
    observation with reward 0."""

    metadata = {"autoreset_mode": gymnasium.vector.AutoresetMode.NEXT_STEP}

    def __init__(self, env_id: str, num_envs: int, level: str = "coarse", **overrides: Any):
        self._env = _hgym.VecEnv(env_id, num_envs, level, _overrides(overrides))
        self.num_envs = num_envs
        low, high = self._env.observation_bounds()
        self.single_observation_space = spaces.Box(low, high, dtype=np.float32)
        low, high = self._env.action_bounds()
        self.single_action_space = spaces.Box(low, high, dtype=np.float32)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._done = np.zeros(num_envs, dtype=bool)
        self._rng = np.random.default_rng()
        self.env_id = env_id
        self.level = level

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        """Resets every instance: ``seed`` an int gives instance ``i`` the seed ``seed + i`` (as
        Gymnasium's vector envs do), a list one seed each, ``None`` seeds drawn at random."""
        if seed is None:
            seeds = [_seed(self._rng) for _ in range(self.num_envs)]
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(self.num_envs)]
            self._rng = np.random.default_rng(int(seed))
        else:
            seeds = [int(s) for s in seed]
            self._rng = np.random.default_rng(seeds[0] if seeds else None)
        obs, infos = self._env.reset(seeds)
        self._done[:] = False
        return obs, _stack(infos)

    def step(self, actions):
        a = np.ascontiguousarray(actions, dtype=np.float64).reshape(self.num_envs, -1)
        resets = [_seed(self._rng) if d else None for d in self._done]
        obs, rewards, terminated, truncated, infos = self._env.step(a, resets)
        terminated = np.asarray(terminated, dtype=bool)
        truncated = np.asarray(truncated, dtype=bool)
        self._done = terminated | truncated
        return obs, np.asarray(rewards, dtype=np.float64), terminated, truncated, _stack(infos)


def _stack(infos: list[dict]) -> dict:
    """Gymnasium's vector info: each key an array over instances, with a ``_key`` mask."""
    out: dict = {}
    n = len(infos)
    for i, info in enumerate(infos):
        for k, v in info.items():
            if k not in out:
                out[k] = np.zeros(n, dtype=object if isinstance(v, str) else np.float64)
                out["_" + k] = np.zeros(n, dtype=bool)
            out[k][i] = v
            out["_" + k][i] = True
    return out
