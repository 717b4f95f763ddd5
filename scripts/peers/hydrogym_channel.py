"""HydroGym's JAX channel (hydrogym 1.0.0, `hydrogym.jax.envs.channel.ChannelFlowSpectralEnv`) as
hgym's peer for `hgym bench channel --peer`.

A line protocol on stdin/stdout, so that hgym interleaves its own measurements with this one's
in one process lifetime (A B A B):

    ready  -> {"peer": "hydrogym <version>", "n": [nx, ny, nz], "length": [lx, ly, lz], "dt": ..., ...}
              grid and box in hgym's order (x streamwise, y wall-normal, z spanwise; the env's
              own order is x, spanwise, wall-normal)
    run    -> {"steps_per_s": ..., "bulk_time_per_s": ..., "steps": n}
              one control interval of the env (its `nsteps` RK4 steps at its `dt`) through the
              jitted forward scan of its solver (`run_channel_pseudospectral`); the env's own
              `step` also differentiates the wall shear through the interval, which is not timed

The env as HydroGym ships it: 72^3 Fourier-Fourier-Chebyshev, box 2 pi x pi x 2, nu 1.9e-3, bulk
velocity held at 8 (outer units: half-height 1, so its bulk time unit is 1/8), dt 2e-4, its
default float32. Its initial field comes from the Hugging Face Hub, out of reach here: a laminar
profile with seeded noise is written for it instead (the cost of a step does not depend on the
field). Usage: hydrogym_channel.py THREADS.
"""

import json
import os
import sys
import tempfile
import time

threads = int(sys.argv[1]) if len(sys.argv) > 1 else 1
os.environ.setdefault("JAX_PLATFORMS", "cpu")
if threads == 1:
    os.environ["XLA_FLAGS"] = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"

import hydrogym  # noqa: E402
import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
from hydrogym.jax.envs.channel import ChannelFlowSpectralEnv, run_channel_pseudospectral  # noqa: E402
from hydrogym.jax.utils.utils import cheb_D_matrices  # noqa: E402

N = 72
LZ = 2.0
U_BULK = 8.0


def initial_field(directory):
    """Laminar Poiseuille flow of bulk 8 on the Chebyshev nodes, with 10 % seeded noise."""
    z, _, _ = cheb_D_matrices(N, LZ)
    z = np.asarray(z)
    rng = np.random.default_rng(0)
    u = 1.5 * U_BULK * (1.0 - z**2)[None, None, :] * np.ones((N, N, 1))
    noise = lambda: 0.1 * U_BULK * rng.standard_normal((N, N, N)) * (1.0 - z**2)[None, None, :]
    for name, f in [("U", u + noise()), ("V", noise()), ("W", noise())]:
        np.save(os.path.join(directory, f"{name}.npy"), f)


def main():
    with tempfile.TemporaryDirectory() as d:
        initial_field(d)
        env = ChannelFlowSpectralEnv({"initial_field_dir": d})
    params = env.default_params
    dt, nsteps = float(params.dt), int(params.nsteps)
    zero = jnp.zeros(params.action_dim, dtype=env.dtype)
    run = jax.jit(
        lambda u, v, w: run_channel_pseudospectral(
            u, v, w, zero, dt, env.equation, env.integrator, nsteps=nsteps, checkpoint_steps=False
        )
    )
    state = (env.U0, env.V0, env.W0)
    state = run(*state)  # compiles
    jax.block_until_ready(state[0])
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        if words[0] == "ready":
            out = {
                "peer": f"hydrogym {getattr(hydrogym, '__version__', '1.0.0')}",
                "jax": jax.__version__,
                "dtype": str(jnp.dtype(env.dtype)),
                "n": [env.Nx, env.Nz, env.Ny],
                "length": [float(env.Lx), float(env.Lz), float(env.Ly)],
                "dt": dt,
                "u_bulk": U_BULK,
                "nu": float(env.nu),
                "steps_per_action": nsteps,
                "threads": threads,
            }
        elif words[0] == "run":
            t = time.perf_counter()
            state = run(*state)
            jax.block_until_ready(state[0])
            wall = time.perf_counter() - t
            out = {
                "steps_per_s": nsteps / wall,
                "bulk_time_per_s": nsteps * dt * U_BULK / (LZ / 2) / wall,
                "steps": nsteps,
            }
        else:
            out = {"error": f"unknown command {words[0]!r}"}
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
