"""Stable-Baselines3 TD3 as hgym's peer for `hgym bench agents --peer`.

A line protocol on stdin/stdout, so that hgym interleaves its own measurements with this one's
in one process lifetime (A B A B):

    ready                      -> {"peer": "stable-baselines3 <version>", "torch": "<version>", "threads": n}
    td3 <n>                    -> {"updates_per_s": ...}   n gradient steps of TD3's train()
    policy <reps>              -> {"us": ...}              batch-1 deterministic predict(), microseconds

The shapes are hgym's: observation 60, action 1, actor and critics 256x256, batch 256, a replay
buffer of 10 000 random transitions. Usage: sb3_td3.py THREADS.
"""

import json
import sys
import time

import numpy as np

threads = int(sys.argv[1]) if len(sys.argv) > 1 else 1

import torch  # noqa: E402

torch.set_num_threads(threads)

import gymnasium as gym  # noqa: E402
import stable_baselines3 as sb3  # noqa: E402
from stable_baselines3 import TD3  # noqa: E402

OBS, ACT = 60, 1


class Dummy(gym.Env):
    observation_space = gym.spaces.Box(-np.inf, np.inf, (OBS,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (ACT,), np.float32)

    def reset(self, seed=None, options=None):
        return np.zeros(OBS, np.float32), {}

    def step(self, action):
        return np.zeros(OBS, np.float32), 0.0, False, False, {}


def main():
    rng = np.random.default_rng(1)
    model = TD3(
        "MlpPolicy",
        Dummy(),
        policy_kwargs={"net_arch": [256, 256]},
        batch_size=256,
        buffer_size=100_000,
        learning_starts=0,
        device="cpu",
        seed=0,
    )
    from stable_baselines3.common.logger import configure

    model.set_logger(configure(None, []))
    for _ in range(10_000):
        s, s2 = rng.standard_normal((2, 1, OBS)).astype(np.float32)
        a = rng.uniform(-1, 1, (1, ACT)).astype(np.float32)
        model.replay_buffer.add(s, s2, a, rng.standard_normal(1).astype(np.float32), np.array([False]), [{}])
    model.train(gradient_steps=10, batch_size=256)
    obs = rng.standard_normal(OBS).astype(np.float32)
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        if words[0] == "ready":
            out = {"peer": f"stable-baselines3 {sb3.__version__}", "torch": torch.__version__, "threads": threads}
        elif words[0] == "td3":
            n = int(words[1])
            t = time.perf_counter()
            model.train(gradient_steps=n, batch_size=256)
            out = {"updates_per_s": n / (time.perf_counter() - t)}
        elif words[0] == "policy":
            reps = int(words[1])
            for _ in range(100):
                model.predict(obs, deterministic=True)
            t = time.perf_counter()
            for _ in range(reps):
                model.predict(obs, deterministic=True)
            out = {"us": (time.perf_counter() - t) * 1e6 / reps}
        else:
            out = {"error": f"unknown command {words[0]!r}"}
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
