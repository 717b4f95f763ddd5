"""hgym's Python package timed for `hgym bench python`, beside the same environments stepped
in Rust by the benchmark itself (alternating: Rust, Python, Rust, ...).

A line protocol on stdin/stdout (the one `hgym bench kolmogorov --peer` speaks):

    ready                          -> {"hgym": version, "gymnasium": ..., "numpy": ..., "python": ...}
    env ID LEVEL SEED OVERRIDES    -> {"obs_dim": ..., "act_dim": ...}
                                      makes `hgym.HgymEnv(ID, LEVEL, **OVERRIDES)` (OVERRIDES a JSON
                                      object without spaces) and `gymnasium.make` of the same, and
                                      resets both with SEED
    steps N                        -> {"s_per_step": ..., "s_in_rust": ..., "s_per_step_gym": ..., "s_in_rust_gym": ...}
                                      N zero actions through `HgymEnv.step` (the boundary: numpy in,
                                      numpy and a dict out, the GIL released), then N through
                                      `gymnasium.make`'s wrappers (Gymnasium's own checks, for scale);
                                      each with the seconds per step spent inside the Rust step
    vec N ID LEVEL SEED OVERRIDES  -> {"num_envs": N}: `hgym.make_vec`, reset with SEED
    vsteps K                       -> {"env_steps_per_s": ...}: K steps of the vector env
    action                         -> {"s_per_action": ...}: one action of the last `env`

Usage: hgym_python.py THREADS (the Rust threads of the vector env: RAYON_NUM_THREADS).
"""

import json
import os
import platform
import sys
import time

threads = int(sys.argv[1]) if len(sys.argv) > 1 else 1
os.environ["RAYON_NUM_THREADS"] = str(threads)


def answer(out):
    print(json.dumps(out), flush=True)


try:
    import gymnasium
    import numpy as np

    import hgym
except ImportError as e:  # answered to `ready`, so hgym names the fix
    for _ in sys.stdin:
        answer({"error": f"{e} in {sys.executable}: run `make python` (or pip install ./python) into it"})
        sys.exit(1)


def main():
    env = wrapped = vec = None
    zero = vzero = None
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        cmd = words[0]
        if cmd == "ready":
            out = {
                "hgym": hgym.__version__,
                "gymnasium": gymnasium.__version__,
                "numpy": np.__version__,
                "python": platform.python_version(),
                "threads": threads,
            }
        elif cmd == "env":
            env_id, level, seed, overrides = words[1], words[2], int(words[3]), json.loads(words[4])
            env = hgym.HgymEnv(env_id, level=level, **overrides)
            wrapped = gymnasium.make(f"hgym/{env_id}-v0", level=level, **overrides)
            env.reset(seed=seed)
            wrapped.reset(seed=seed)
            zero = np.zeros(env.action_space.shape, dtype=np.float32)
            out = {"obs_dim": int(env.observation_space.shape[0]), "act_dim": int(zero.shape[0])}
        elif cmd == "steps":
            n = int(words[1])
            out = {}
            for key, e, inner in [("", env, env._env), ("_gym", wrapped, wrapped.unwrapped._env)]:
                inside = inner.step_seconds
                t = time.perf_counter()
                for _ in range(n):
                    e.step(zero)
                out["s_per_step" + key] = (time.perf_counter() - t) / n
                out["s_in_rust" + key] = (inner.step_seconds - inside) / n
        elif cmd == "vec":
            n, env_id, level, seed, overrides = int(words[1]), words[2], words[3], int(words[4]), json.loads(words[5])
            vec = hgym.make_vec(env_id, n, level=level, **overrides)
            vec.reset(seed=seed)
            vzero = np.zeros(vec.action_space.shape, dtype=np.float32)
            out = {"num_envs": n}
        elif cmd == "vsteps":
            k = int(words[1])
            t = time.perf_counter()
            for _ in range(k):
                vec.step(vzero)
            out = {"env_steps_per_s": k * vec.num_envs / (time.perf_counter() - t)}
        elif cmd == "action":
            t = time.perf_counter()
            env.step(zero)
            out = {"s_per_action": time.perf_counter() - t}
        else:
            out = {"error": f"unknown command {cmd!r}"}
        answer(out)


if __name__ == "__main__":
    main()
