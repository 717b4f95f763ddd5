"""TD3 on an hgym flow in the style of CleanRL's `td3_continuous_action.py` (one file, no
framework): Fujimoto, van Hoof & Meger 2018, through hgym's vector environment.

    pip install ./python torch
    python examples/td3_cleanrl.py --env-id Cylinder_2D_Re100 --num-envs 2 --total-timesteps 20000

The environments come from `gymnasium.make_vec("hgym/<ID>-v0", num_envs=n)`, which builds hgym's
own vector env (n flows stepped on Rust threads in one call); Gymnasium's episode statistics
wrapper reports the returns. The vector env resets a finished instance on its next step
(Gymnasium's next-step autoreset), so the transition out of a finished episode into the next
one's first observation is not stored.
"""

import argparse
import json
import random
import time

import gymnasium as gym
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

import hgym  # noqa: F401  registers hgym/<ID>-v0


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--env-id", default="Cylinder_2D_Re100", help="an hgym ID (`hgym envs` lists them)")
    p.add_argument("--level", default="coarse", choices=["coarse", "default", "fine"])
    p.add_argument("--episode-actions", type=int, default=None, help="override the spec's episode length")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--num-envs", type=int, default=2)
    p.add_argument("--total-timesteps", type=int, default=20_000, help="environment steps over all instances")
    p.add_argument("--learning-rate", type=float, default=3e-4)
    p.add_argument("--buffer-size", type=int, default=1_000_000)
    p.add_argument("--gamma", type=float, default=0.99)
    p.add_argument("--tau", type=float, default=0.005)
    p.add_argument("--batch-size", type=int, default=256)
    p.add_argument("--exploration-noise", type=float, default=0.1)
    p.add_argument("--learning-starts", type=int, default=2_000)
    p.add_argument("--policy-frequency", type=int, default=2)
    p.add_argument("--policy-noise", type=float, default=0.2)
    p.add_argument("--noise-clip", type=float, default=0.5)
    p.add_argument("--torch-threads", type=int, default=1, help="torch's CPU threads (the flows use their own)")
    p.add_argument("--save", default=None, help="write the actor's weights here at the end")
    return p.parse_args()


class QNetwork(nn.Module):
    def __init__(self, obs_dim, act_dim):
        super().__init__()
        self.fc1 = nn.Linear(obs_dim + act_dim, 256)
        self.fc2 = nn.Linear(256, 256)
        self.fc3 = nn.Linear(256, 1)

    def forward(self, x, a):
        x = F.relu(self.fc1(torch.cat([x, a], 1)))
        return self.fc3(F.relu(self.fc2(x)))


class Actor(nn.Module):
    def __init__(self, obs_dim, low, high):
        super().__init__()
        self.fc1 = nn.Linear(obs_dim, 256)
        self.fc2 = nn.Linear(256, 256)
        self.fc_mu = nn.Linear(256, len(low))
        self.register_buffer("action_scale", torch.tensor((high - low) / 2.0, dtype=torch.float32))
        self.register_buffer("action_bias", torch.tensor((high + low) / 2.0, dtype=torch.float32))

    def forward(self, x):
        x = F.relu(self.fc2(F.relu(self.fc1(x))))
        return torch.tanh(self.fc_mu(x)) * self.action_scale + self.action_bias


class ReplayBuffer:
    """Transitions in preallocated numpy arrays, overwritten oldest first."""

    def __init__(self, size, obs_dim, act_dim, rng):
        self.obs = np.zeros((size, obs_dim), np.float32)
        self.next_obs = np.zeros((size, obs_dim), np.float32)
        self.actions = np.zeros((size, act_dim), np.float32)
        self.rewards = np.zeros(size, np.float32)
        self.dones = np.zeros(size, np.float32)
        self.size, self.n, self.pos, self.rng = size, 0, 0, rng

    def add(self, obs, next_obs, action, reward, done):
        i = self.pos
        self.obs[i], self.next_obs[i], self.actions[i], self.rewards[i], self.dones[i] = obs, next_obs, action, reward, done
        self.pos = (self.pos + 1) % self.size
        self.n = min(self.n + 1, self.size)

    def sample(self, batch):
        idx = self.rng.integers(0, self.n, batch)
        t = lambda a: torch.as_tensor(a[idx])  # noqa: E731
        return t(self.obs), t(self.actions), t(self.next_obs), t(self.rewards), t(self.dones)


def main():
    args = parse_args()
    random.seed(args.seed)
    np.random.seed(args.seed)
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.torch_threads)
    rng = np.random.default_rng(args.seed)

    overrides = {} if args.episode_actions is None else {"episode_actions": args.episode_actions}
    envs = gym.make_vec(f"hgym/{args.env_id}-v0", num_envs=args.num_envs, level=args.level, **overrides)
    envs = gym.wrappers.vector.RecordEpisodeStatistics(envs)
    obs_dim = envs.single_observation_space.shape[0]
    low, high = envs.single_action_space.low, envs.single_action_space.high
    act_dim = len(low)

    actor, target_actor = Actor(obs_dim, low, high), Actor(obs_dim, low, high)
    qf1, qf2 = QNetwork(obs_dim, act_dim), QNetwork(obs_dim, act_dim)
    qf1_target, qf2_target = QNetwork(obs_dim, act_dim), QNetwork(obs_dim, act_dim)
    target_actor.load_state_dict(actor.state_dict())
    qf1_target.load_state_dict(qf1.state_dict())
    qf2_target.load_state_dict(qf2.state_dict())
    q_optimizer = torch.optim.Adam(list(qf1.parameters()) + list(qf2.parameters()), lr=args.learning_rate)
    actor_optimizer = torch.optim.Adam(actor.parameters(), lr=args.learning_rate)
    rb = ReplayBuffer(min(args.buffer_size, args.total_timesteps), obs_dim, act_dim, rng)

    start = time.time()
    returns, updates = [], 0
    obs, _ = envs.reset(seed=args.seed)
    finished = np.zeros(args.num_envs, dtype=bool)  # instances the next step resets
    for global_step in range(0, args.total_timesteps, args.num_envs):
        if global_step < args.learning_starts:
            actions = rng.uniform(low, high, (args.num_envs, act_dim)).astype(np.float32)
        else:
            with torch.no_grad():
                actions = actor(torch.as_tensor(obs)).numpy()
                actions += rng.normal(0.0, actor.action_scale.numpy() * args.exploration_noise, actions.shape)
                actions = actions.clip(low, high).astype(np.float32)

        next_obs, rewards, terminations, truncations, infos = envs.step(actions)
        if "episode" in infos:
            for i in np.flatnonzero(infos["_episode"]):
                returns.append(float(infos["episode"]["r"][i]))
                print(f"global_step={global_step}, episodic_return={returns[-1]:.4f}, length={int(infos['episode']['l'][i])}")

        for i in range(args.num_envs):
            if not finished[i]:  # a step that reset instance i is not a transition
                rb.add(obs[i], next_obs[i], actions[i], rewards[i], float(terminations[i]))
        finished = terminations | truncations
        obs = next_obs

        if global_step >= args.learning_starts and rb.n >= args.batch_size:
            b_obs, b_actions, b_next_obs, b_rewards, b_dones = rb.sample(args.batch_size)
            with torch.no_grad():
                clipped_noise = (torch.randn_like(b_actions) * args.policy_noise).clamp(-args.noise_clip, args.noise_clip)
                clipped_noise = clipped_noise * target_actor.action_scale
                next_actions = (target_actor(b_next_obs) + clipped_noise).clamp(torch.as_tensor(low), torch.as_tensor(high))
                q_next = torch.min(qf1_target(b_next_obs, next_actions), qf2_target(b_next_obs, next_actions)).view(-1)
                target = b_rewards + (1 - b_dones) * args.gamma * q_next
            qf_loss = F.mse_loss(qf1(b_obs, b_actions).view(-1), target) + F.mse_loss(qf2(b_obs, b_actions).view(-1), target)
            q_optimizer.zero_grad()
            qf_loss.backward()
            q_optimizer.step()
            updates += 1

            if (global_step // args.num_envs) % args.policy_frequency == 0:
                actor_loss = -qf1(b_obs, actor(b_obs)).mean()
                actor_optimizer.zero_grad()
                actor_loss.backward()
                actor_optimizer.step()
                with torch.no_grad():
                    for net, target_net in ((actor, target_actor), (qf1, qf1_target), (qf2, qf2_target)):
                        for p, tp in zip(net.parameters(), target_net.parameters()):
                            tp.mul_(1 - args.tau).add_(args.tau * p)

    envs.close()
    if args.save:
        torch.save(actor.state_dict(), args.save)
    summary = {
        "env_id": args.env_id,
        "level": args.level,
        "steps": args.total_timesteps,
        "episodes": len(returns),
        "critic_updates": updates,
        "first_return": returns[0] if returns else None,
        "last_return": returns[-1] if returns else None,
        "seconds": round(time.time() - start, 2),
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
