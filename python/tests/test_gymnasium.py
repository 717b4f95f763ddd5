"""hgym from Python (`make test` runs this with the venv `make setup` builds, after `make
python` installed the wheel): Gymnasium's checker over every ID, observations bitwise those of
the Rust environment, the vector environment bitwise n separate ones, errors with the Rust
messages, and the reward gradient against finite differences."""

import glob
import json
import os
import subprocess
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import hgym

IDS = [e["id"] for e in hgym.envs()]
# Short episodes keep the checker's resets and steps cheap; the flow is the registered one.
SHORT = {"episode_actions": 3}
# The 3D lattice-Boltzmann flows (coarse grids of 0.7 to 4 million nodes) also get a spin-up and a
# control interval of a few lattice steps, on their registered grids.
SHORT_3D = {**SHORT, "spin_up": 0.1, "control_interval": 0.005}
# The wing's boundary layer (a plate of 0.6 million cells at coarse) gets a spin-up of a few steps.
SHORT_WING = {**SHORT, "spin_up": 0.002}
SHORTS = {
    e["id"]: SHORT_3D if e["dimension"] == 3 and e["solver"].startswith("lbm") else SHORT_WING if e["family"] == "wing_tbl" else SHORT
    for e in hgym.envs()
}
# Gymnasium's checker runs over every 2D and spectral ID, and over the first 3D lattice-Boltzmann ID
# of each family: the binding is one code path per family (each 3D check costs 3-27 s here); the
# Rust contract checks every 3D ID in `make nightly` (tests/env3_contract.rs, an ignored test).
FIRST_3D = {}
for e in hgym.envs():
    if SHORTS[e["id"]] is SHORT_3D:
        FIRST_3D.setdefault(e["family"], e["id"])
CHECKED = [i for i in IDS if SHORTS[i] is not SHORT_3D or i in FIRST_3D.values()]


def hgym_binary() -> str:
    target = os.environ.get("CARGO_TARGET_DIR", os.path.expanduser("~/.cache/hgym-target"))
    return os.environ.get("HGYM", os.path.join(target, "release", "hgym"))


def test_every_id_is_registered_with_its_spec():
    assert len(IDS) >= 35
    for e in hgym.envs():
        spec = gym.spec(f"hgym/{e['id']}-v0")
        assert spec.kwargs["env_id"] == e["id"]
        assert e["obs_dim"] > 0 and e["act_dim"] > 0 and e["control_interval"] > 0


@pytest.mark.parametrize("env_id", CHECKED)
def test_gymnasium_check_env_passes_at_coarse(env_id):
    env = gym.make(f"hgym/{env_id}-v0", level="coarse", render_mode="rgb_array", **SHORTS[env_id])
    check_env(env.unwrapped, skip_render_check=False)
    env.reset(seed=0)
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    env.close()


def test_observations_are_the_rust_environments_bitwise(tmp_path):
    """`hgym eval --policy zero` and the Python env from the same seed: the same observations
    (float32 of the Rust float64) and the same rewards, every step."""
    env_id, seed = "Kolmogorov_2D_Re40", 7
    out = subprocess.run(
        [hgym_binary(), "eval", "--policy", "zero", "--env", env_id, "--episodes", "1",
         "--eval-seed", str(seed), "--out", str(tmp_path)],
        capture_output=True, text=True,
    )
    assert out.returncode == 0, out.stderr
    from mcap.reader import make_reader

    obs_rust, rewards_rust = [], []
    with open(glob.glob(str(tmp_path / "**" / "trajectory.mcap"), recursive=True)[0], "rb") as f:
        for _, channel, message in make_reader(f).iter_messages(topics=["/obs", "/reward"]):
            body = json.loads(message.data)
            if channel.topic == "/obs":
                obs_rust.append(np.array(body["obs"], dtype=np.float64))
            else:
                rewards_rust.append(body["reward"])

    env = gym.make(f"hgym/{env_id}-v0")
    obs, _ = env.reset(seed=seed)
    obs_py, rewards_py = [obs], []
    zero = np.zeros(env.action_space.shape, dtype=np.float32)
    while True:
        obs, reward, terminated, truncated, _ = env.step(zero)
        obs_py.append(obs)
        rewards_py.append(reward)
        if terminated or truncated:
            break
    assert len(obs_py) == len(obs_rust) and len(rewards_py) == len(rewards_rust) > 1
    for k, (a, b) in enumerate(zip(obs_py, obs_rust)):
        assert np.array_equal(a, b.astype(np.float32)), f"observation {k} differs"
    assert rewards_py == rewards_rust


@pytest.mark.parametrize("env_id", ["Kolmogorov_2D_Re40", "Cylinder_2D_Re100"])
def test_the_vector_env_is_n_separate_envs_bitwise(env_id):
    n, steps = 3, SHORT["episode_actions"]
    rng = np.random.default_rng(0)
    vec = hgym.make_vec(env_id, n, **SHORT)
    actions = rng.uniform(-1, 1, (steps,) + vec.action_space.shape)
    obs, _ = vec.reset(seed=11)
    rows, rewards = [obs], []
    for a in actions:
        obs, reward, *_ = vec.step(a)
        rows.append(obs)
        rewards.append(reward)
    for i in range(n):
        env = gym.make(f"hgym/{env_id}-v0", **SHORT)
        o, _ = env.reset(seed=11 + i)
        assert np.array_equal(o, rows[0][i])
        for k, a in enumerate(actions):
            o, r, *_ = env.step(a[i])
            assert np.array_equal(o, rows[k + 1][i]) and r == rewards[k][i], (i, k)


def test_the_vector_env_autoresets_on_the_next_step():
    vec = hgym.make_vec("Kolmogorov_2D_Re40", 2, episode_actions=2)
    vec.reset(seed=0)
    zero = np.zeros(vec.action_space.shape)
    _, _, _, truncated, _ = vec.step(zero)
    assert not truncated.any()
    _, _, _, truncated, _ = vec.step(zero)
    assert truncated.all()
    obs, reward, terminated, truncated, _ = vec.step(zero)
    assert (reward == 0).all() and not (terminated | truncated).any()
    assert obs.shape == vec.observation_space.shape


def test_every_action_form_steps_bitwise_alike():
    """float32 and float64 arrays go to Rust as they are (float32 widened exactly); lists,
    strided arrays and other shapes are converted by `HgymEnv.step`: all give one trajectory."""
    a64 = np.random.default_rng(1).uniform(-1, 1, (3, 4)).astype(np.float32).astype(np.float64)
    forms = [
        lambda a: a,
        lambda a: a.astype(np.float32),
        lambda a: a.tolist(),
        lambda a: np.repeat(a, 2)[::2],
        lambda a: a.reshape(1, -1),
    ]
    runs = []
    for form in forms:
        env = hgym.HgymEnv("Kolmogorov_2D_Re40", episode_actions=3)
        env.reset(seed=5)
        before = env._env.step_seconds
        runs.append([env.step(form(a))[0] for a in a64])
        assert env._env.step_seconds > before
    for run in runs[1:]:
        assert all(np.array_equal(x, y) for x, y in zip(runs[0], run))


def test_errors_arrive_with_the_rust_message():
    with pytest.raises(ValueError, match="did you mean 'Cylinder_2D_Re100'"):
        hgym.HgymEnv("Cylindr_2D_Re100")
    with pytest.raises(ValueError, match="unknown field `nope`"):
        gym.make("hgym/Kolmogorov_2D_Re40-v0", nope=3)
    with pytest.raises(ValueError, match="episode_actions must be 1 to"):
        gym.make("hgym/Cylinder_2D_Re100-v0", episode_actions=0)
    with pytest.raises(ValueError, match="level 'medium'"):
        gym.make("hgym/Cylinder_2D_Re100-v0", level="medium")
    env = gym.make("hgym/Kolmogorov_2D_Re40-v0").unwrapped
    with pytest.raises(RuntimeError, match="call reset first"):
        env.step(np.zeros(env.action_space.shape))
    env.reset(seed=0)
    bad = np.zeros(env.action_space.shape)
    bad[1] = np.nan
    with pytest.raises(ValueError, match="action component 1 is NaN"):
        env.step(bad)
    with pytest.raises(ValueError, match="action has 1 components"):
        env.step(np.zeros(1))


def test_the_reward_gradient_matches_finite_differences():
    """d(reward of the last step)/d(its action) from the adjoint, against central differences
    of the same step replayed from the same state (reset with the same seed, same history)."""
    env_id, seed = "Kolmogorov_2D_Re40", 3
    rng = np.random.default_rng(1)
    env = gym.make(f"hgym/{env_id}-v0").unwrapped
    history = rng.uniform(-0.5, 0.5, (3,) + env.action_space.shape)

    def last_reward(last):
        env.reset(seed=seed)
        for a in history[:-1]:
            env.step(a)
        return env.step(last)[1]

    last_reward(history[-1])
    grad = env.reward_action_gradients(1)[0]
    eps = 1e-5
    for j in range(len(grad)):
        up, down = history[-1].copy(), history[-1].copy()
        up[j] += eps
        down[j] -= eps
        fd = (last_reward(up) - last_reward(down)) / (2 * eps)
        assert abs(grad[j] - fd) <= 1e-5 * max(1.0, abs(fd)), (j, grad[j], fd)
