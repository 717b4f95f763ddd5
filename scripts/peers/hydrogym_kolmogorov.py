"""HydroGym's JAX Kolmogorov environment (hydrogym 1.0.0) as hgym's peer for
`hgym bench kolmogorov --peer`.

A line protocol on stdin/stdout, so that hgym interleaves its own measurements with this one's
in one process lifetime (A B A B):

    ready          -> {"peer": "hydrogym <version>", "jax": "<version>", "x64": bool, "dt": 0.001, ...}
    action [N]     -> {"steps_per_s": ..., "s_per_action": ..., "steps": n, "n": N}
                      one control action (the env's action time at its dt) on an N x N grid
                      (64 if not given) through the env's jitted `step_env`: gymnax's `step` also
                      runs `reset_env` on every call for its auto-reset (a second rollout of the
                      same length), which is not counted
    gym_action     -> {"s_per_action": ...}
                      one control action through gymnax's Gymnasium wrapper (`GymnaxToGymWrapper`,
                      what a Gymnasium user steps: the jitted `step` with its auto-reset rollout)
    accuracy       -> {"dt": ..., "reference_dt": ..., "relative_error": ...}
                      the relative L2 error of the vorticity after one action at the env's dt
                      against the same action at a quarter of it, from the same developed state

Set-up as hgym's bench: Re 40, k_f 4, N = 64 (or 128), dt 1e-3 (the env's default), float64
(JAX_ENABLE_X64=1; the env runs in float32 otherwise). Two adaptations to hydrogym 1.0.0 with
gymnax 1.0.1, made here and not in the installed files: gymnax's `step` calls `is_terminated`,
which the env does not define (it is given the env's own `terminal` flag); the env's action time
is fixed at 10 time units (its integrator refuses less than 1). Usage: hydrogym_kolmogorov.py THREADS.
"""

import json
import os
import sys
import time

threads = int(sys.argv[1]) if len(sys.argv) > 1 else 1
os.environ.setdefault("JAX_ENABLE_X64", "1")
os.environ.setdefault("JAX_PLATFORMS", "cpu")
if threads == 1:
    os.environ["XLA_FLAGS"] = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"

import hydrogym  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from gymnax.wrappers.gym import GymnaxToGymWrapper  # noqa: E402
from hydrogym.jax.envs.kolmogorov import KolmogorovFlow  # noqa: E402

KolmogorovFlow.is_terminated = lambda self, state, params: state.terminal

DT = 1e-3


def make(dt, n=64):
    """The env at step `dt` on an n x n grid and its jitted transition without gymnax's auto-reset."""
    env = KolmogorovFlow(env_config={"dt": dt}, flow_config={"Re": 40, "k": 4, "grid_size": (n, n)})
    params = env.default_params
    step = jax.jit(lambda key, state, action: env.step_env(key, state, action, params)[1])
    return env, params, step


def developed(n):
    """The env on an n x n grid, its developed state (two actions from the env's initial state,
    which also compile the step), its jitted step and the integrator's steps per action:
    `action_time // dt` rounded down to whole saving intervals of `save_time // dt` steps (9990
    at dt 1e-3)."""
    key = jax.random.PRNGKey(0)
    env, params, step = make(DT, n)
    _, state = env.reset(key, params)
    for _ in range(2):
        state = step(key, state, jnp.zeros(4))
    jax.block_until_ready(state.omega_hat)
    per_save = int(params.save_time // params.dt)
    steps = int(params.action_time // params.dt) // per_save * per_save
    return {"env": env, "params": params, "step": step, "state": state, "steps": steps}


def main():
    key = jax.random.PRNGKey(0)
    zero = jnp.zeros(4)
    grids = {64: developed(64)}
    params = grids[64]["params"]
    gym_env = None
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        if words[0] == "ready":
            out = {
                "peer": f"hydrogym {getattr(hydrogym, '__version__', '1.0.0')}",
                "jax": jax.__version__,
                "x64": bool(jax.config.read("jax_enable_x64")),
                "dt": float(params.dt),
                "action_time": float(params.action_time),
                "n": 64,
                "threads": threads,
            }
        elif words[0] == "action":
            n = int(words[1]) if len(words) > 1 else 64
            if n not in grids:
                grids[n] = developed(n)
            g = grids[n]
            t = time.perf_counter()
            g["state"] = g["step"](key, g["state"], zero)
            jax.block_until_ready(g["state"].omega_hat)
            wall = time.perf_counter() - t
            out = {"steps_per_s": g["steps"] / wall, "s_per_action": wall, "steps": g["steps"], "n": n}
        elif words[0] == "gym_action":
            if gym_env is None:
                # A fresh env: the wrapper deep-copies it, and `env` holds tracers from `step`'s jit.
                fresh, fresh_params, _ = make(DT)
                gym_env = GymnaxToGymWrapper(fresh, fresh_params)
                gym_env.reset(seed=0)
                jax.block_until_ready(gym_env.step(zero)[0])  # compiles
            t = time.perf_counter()
            jax.block_until_ready(gym_env.step(zero)[0])
            out = {"s_per_action": time.perf_counter() - t}
        elif words[0] == "accuracy":
            _, _, fine_step = make(DT / 4)
            step, state = grids[64]["step"], grids[64]["state"]
            a = step(key, state, zero).omega_hat
            b = fine_step(key, state, zero).omega_hat
            err = float(jnp.linalg.norm(a - b) / jnp.linalg.norm(b))
            out = {"dt": DT, "reference_dt": DT / 4, "relative_error": err}
        else:
            out = {"error": f"unknown command {words[0]!r}"}
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
