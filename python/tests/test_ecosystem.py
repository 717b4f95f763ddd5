"""hgym with the Python RL ecosystem (`make test`, the venv `make setup` builds): Stable-Baselines3's
checker on one ID of each family, SB3 PPO training 2,048 steps on the cylinder, the torch
autograd Function against finite differences, and the examples (CleanRL-style TD3 through the
vector env, the JAX custom_vjp) run as a user runs them."""

import json
import re
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import hgym
import hgym.torch

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SHORT = {"episode_actions": 3}
# The first ID of each family, in registry order, with its checker settings (3D lattice-Boltzmann
# flows also a spin-up and control interval of a few lattice steps).
FIRST = {}
SHORTS = {}
for e in hgym.envs():
    FIRST.setdefault(e["family"], e["id"])
    lbm_3d = e["dimension"] == 3 and e["solver"].startswith("lbm")
    SHORTS[e["id"]] = {**SHORT, "spin_up": 0.1, "control_interval": 0.005} if lbm_3d else SHORT
    if e["family"] == "wing_tbl":
        SHORTS[e["id"]] = {**SHORT, "spin_up": 0.002}
FAMILIES = list(FIRST.values())

@pytest.mark.parametrize("env_id", FAMILIES)
def test_sb3_check_env_passes(env_id):
    env = gym.make(f"hgym/{env_id}-v0", level="coarse", **SHORTS[env_id]).unwrapped
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sb3_check_env(env, warn=True)
    # SB3 warns about spaces it trains badly on (unnormalised or asymmetric boxes, ...): ours
    # are symmetric and normalised, so none is expected.
    messages = [str(w.message) for w in caught if "stable_baselines3" in w.filename or "env_checker" in w.filename]
    assert not messages, messages


def test_sb3_ppo_trains_2048_steps_on_the_cylinder():
    env = gym.make("hgym/Cylinder_2D_Re100-v0", level="coarse")
    torch.set_num_threads(1)
    model = PPO("MlpPolicy", env, n_steps=2048, batch_size=64, seed=0, device="cpu")
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(total_timesteps=2048)
    assert model.num_timesteps == 2048
    assert any(not torch.equal(a, b) for a, b in zip(before, model.policy.parameters())), "PPO did not update"
    assert all(torch.isfinite(p).all() for p in model.policy.parameters())
    episodes = list(model.ep_info_buffer)  # 200 actions each at this spec
    assert len(episodes) == 2048 // 200 and all(e["l"] == 200 and np.isfinite(e["r"]) for e in episodes)


def test_the_torch_function_gives_the_flows_gradient():
    """d(k-step reward)/d(theta) for actions a = tanh(theta) through `hgym.torch.flow_reward`,
    against central differences of the rewards along a random direction."""
    env = gym.make("hgym/Kolmogorov_2D_Re40-v0")
    gen = torch.Generator().manual_seed(0)
    k, act_dim = 3, env.action_space.shape[0]
    theta = (0.3 * torch.randn(k, act_dim, generator=gen, dtype=torch.float64)).requires_grad_()

    def rollout(th):
        env.reset(seed=4)
        return [env.step(a)[1] for a in torch.tanh(th).detach().numpy()]

    rewards = rollout(theta)
    hgym.torch.flow_reward(env, torch.tanh(theta), rewards).backward()
    direction = torch.randn(k, act_dim, generator=gen, dtype=torch.float64)
    eps = 1e-5
    fd = (sum(rollout(theta.detach() + eps * direction)) - sum(rollout(theta.detach() - eps * direction))) / (2 * eps)
    adjoint = float((theta.grad * direction).sum())
    assert abs(adjoint - fd) <= 1e-5 * max(1.0, abs(fd)), (adjoint, fd)


def test_the_torch_function_refuses_actions_the_env_did_not_take():
    env = gym.make("hgym/Kolmogorov_2D_Re40-v0")
    env.reset(seed=0)
    env.step(np.zeros(env.action_space.shape))
    with pytest.raises(ValueError, match="holds 1 steps"):
        hgym.torch.flow_reward(env, torch.zeros(2, env.action_space.shape[0]), [0.0, 0.0])
    with pytest.raises(ValueError, match="2 rewards for 1 actions"):
        hgym.torch.flow_reward(env, torch.zeros(1, env.action_space.shape[0]), [0.0, 0.0])


def run_example(name, *args):
    out = subprocess.run([sys.executable, str(EXAMPLES / name), *args], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_the_cleanrl_td3_example_trains_through_the_vector_env():
    stdout = run_example(
        "td3_cleanrl.py", "--env-id", "Kolmogorov_2D_Re40", "--num-envs", "2", "--episode-actions", "10",
        "--total-timesteps", "60", "--learning-starts", "20", "--batch-size", "16",
    )
    # 30 vector steps; an episode is 10 steps and the autoreset step after it: 2 per instance.
    summary = json.loads(stdout.strip().splitlines()[-1])
    assert summary["episodes"] == 4 and np.isfinite(summary["last_return"]), stdout
    assert stdout.count("episodic_return=") == 4
    # Updates from step 20 on (after the first full batch), one per vector step.
    assert summary["critic_updates"] == (60 - 20) // 2, stdout


def test_the_jax_example_matches_finite_differences():
    stdout = run_example("jax_vjp.py")
    adjoint, fd = map(float, re.search(r"adjoint (\S+), finite differences (\S+)", stdout).groups())
    assert abs(adjoint - fd) <= 1e-5 * max(1.0, abs(fd)), stdout
