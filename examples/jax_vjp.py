"""Differentiating through an hgym flow from JAX with `jax.custom_vjp`.

    pip install ./python jax
    python examples/jax_vjp.py

The differentiable environments (the Kolmogorov family) hold their trajectory since the last
reset; `env.unwrapped.reward_action_gradients(k)` is d(sum of the last k rewards)/d(each of
those k actions), from the flow's discrete adjoint. `flow_reward` below makes that a JAX
function of the actions whose VJP is the adjoint: forward returns the rewards the environment
computed, backward multiplies the cotangent into the gradient. It calls the environment, so it
runs outside `jax.jit`. The script checks the chain rule through an open-loop policy
(a_t = tanh(theta_t)) against finite differences of the rewards.
"""

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np

import hgym  # noqa: F401  registers hgym/<ID>-v0

jax.config.update("jax_enable_x64", True)


def flow_reward(env):
    """``R(actions, rewards)``: the summed reward of ``env``'s last ``len(actions)`` steps,
    differentiable in ``actions`` through the flow's adjoint."""

    @jax.custom_vjp
    def reward(actions, rewards):
        return jnp.sum(rewards)

    def forward(actions, rewards):
        gradient = jnp.asarray(env.unwrapped.reward_action_gradients(actions.shape[0]))
        return jnp.sum(rewards), (gradient, jnp.zeros_like(rewards))

    def backward(saved, cotangent):
        gradient, zero = saved
        return cotangent * gradient, zero  # the recorded rewards are data, not inputs

    reward.defvjp(forward, backward)
    return reward


def rollout(env, theta, seed):
    """The open-loop policy a_t = tanh(theta_t) from reset(seed); returns actions and rewards."""
    env.reset(seed=seed)
    actions = jnp.tanh(theta)
    rewards = [env.step(np.asarray(a))[1] for a in actions]
    return actions, jnp.asarray(rewards)


def main(env_id="Kolmogorov_2D_Re40", k=3, seed=5):
    """d(k-step reward)/d(theta) through the flow's adjoint, against central differences along
    a random direction. Returns both."""
    env = gym.make(f"hgym/{env_id}-v0", level="coarse")
    theta = 0.3 * jax.random.normal(jax.random.PRNGKey(0), (k, env.action_space.shape[0]), dtype=jnp.float64)
    reward = flow_reward(env)

    # The environment steps with the values; the flow's VJP carries the gradient of the recorded
    # rewards back into the actions, and JAX's chain rule through tanh into theta.
    _, rewards = rollout(env, theta, seed)
    grad = jax.grad(lambda th: reward(jnp.tanh(th), rewards))(theta)
    direction = jax.random.normal(jax.random.PRNGKey(1), theta.shape, dtype=jnp.float64)
    eps = 1e-5
    up = float(jnp.sum(rollout(env, theta + eps * direction, seed)[1]))
    down = float(jnp.sum(rollout(env, theta - eps * direction, seed)[1]))
    fd = (up - down) / (2 * eps)
    adjoint = float(jnp.sum(grad * direction))
    print(f"directional derivative of the {k}-step reward: adjoint {adjoint:.8e}, finite differences {fd:.8e}")
    return adjoint, fd


if __name__ == "__main__":
    main()
