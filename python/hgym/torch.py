"""Backpropagating through a differentiable hgym flow with PyTorch.

The differentiable environments (the Kolmogorov family) keep their trajectory since the last
reset and differentiate it with a discrete adjoint: ``env.reward_action_gradients(k)`` is
d(sum of the last k rewards)/d(each of those k actions). :class:`FlowReward` turns that into an
autograd node, so a policy's actions can be trained on the flow's own gradient (the paper's
gradient-enhanced PPO adds this term to its loss)::

    obs, _ = env.reset(seed=0)
    actions, rewards = [], []
    for _ in range(k):
        a = policy(torch.as_tensor(obs))                 # differentiable in the policy's weights
        obs, r, terminated, truncated, _ = env.step(a.detach().numpy())
        actions.append(a); rewards.append(r)
    total = hgym.torch.flow_reward(env, torch.stack(actions), rewards)
    (-total).backward()                                  # d(-reward)/d(weights) through the flow

Requires ``torch`` (not a dependency of the package).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import torch


class FlowReward(torch.autograd.Function):
    """``R(a_1, ..., a_k)``: the summed reward of ``env``'s last ``k`` steps as a function of the
    actions that produced them (``actions`` a ``(k, act_dim)`` tensor, in the order taken).

    Forward returns the rewards the environment already computed (nothing is re-simulated);
    backward is one adjoint sweep of the flow, ``grad * env.reward_action_gradients(k)``.
    Call it after the ``k`` steps and before the next step or reset: the gradient belongs to
    the trajectory the environment holds at that moment."""

    @staticmethod
    def forward(ctx, actions: torch.Tensor, env, rewards: torch.Tensor) -> torch.Tensor:
        if actions.dim() != 2:
            raise ValueError(f"actions must be a (k, act_dim) tensor of the last k actions, got shape {tuple(actions.shape)}")
        k = actions.shape[0]
        if rewards.shape != (k,):
            raise ValueError(f"{rewards.shape[0] if rewards.dim() else 0} rewards for {k} actions: give the reward of each of the last k steps")
        gradient = np.asarray(_unwrapped(env).reward_action_gradients(k))
        if gradient.shape != tuple(actions.shape):
            raise ValueError(
                f"the environment holds {gradient.shape[0]} steps of {gradient.shape[1] if gradient.ndim == 2 else 0} actions "
                f"since its reset; the actions have shape {tuple(actions.shape)}"
            )
        ctx.save_for_backward(torch.as_tensor(gradient, dtype=actions.dtype, device=actions.device))
        return rewards.sum().to(actions.dtype)

    @staticmethod
    def backward(ctx, grad_output: torch.Tensor):
        (gradient,) = ctx.saved_tensors
        return grad_output * gradient, None, None


def flow_reward(env, actions: torch.Tensor, rewards: Sequence[float] | torch.Tensor) -> torch.Tensor:
    """The summed reward of ``env``'s last ``len(actions)`` steps, differentiable in ``actions``
    through the flow's adjoint (:class:`FlowReward`)."""
    rewards = torch.as_tensor(np.asarray(rewards, dtype=np.float64), dtype=actions.dtype, device=actions.device)
    return FlowReward.apply(actions, env, rewards)


def _unwrapped(env):
    """The hgym environment under Gymnasium's wrappers (``gymnasium.make`` adds some)."""
    inner = getattr(env, "unwrapped", env)
    if not hasattr(inner, "reward_action_gradients"):
        raise TypeError(f"{type(inner).__name__} is not an hgym environment with a reward gradient")
    return inner
