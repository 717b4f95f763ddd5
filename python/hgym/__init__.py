"""hgym from Python: every hgym flow environment as a Gymnasium environment.

    import gymnasium as gym
    import hgym  # registers the IDs

    env = gym.make("hgym/Cylinder_2D_Re100-v0", level="coarse")
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

The environments are hgym's own (the Rust ones `hgym train` runs), not re-implementations:
same specs, same seeds, same numbers. Keyword arguments of ``gym.make`` other than ``level``
and ``render_mode`` override spec fields, as ``[env]`` does in a train config.
"""

from hgym._hgym import __version__
from hgym.env import HgymEnv, HgymVectorEnv, envs, make_vec

__all__ = ["HgymEnv", "HgymVectorEnv", "envs", "make_vec", "register_envs", "__version__"]


def register_envs():
    """Registers every hgym ID with Gymnasium as ``hgym/<ID>-v0`` (done on import)."""
    import gymnasium

    for spec in envs():
        name = f"hgym/{spec['id']}-v0"
        if name not in gymnasium.registry:
            gymnasium.register(
                id=name,
                entry_point="hgym.env:HgymEnv",
                kwargs={"env_id": spec["id"]},
                vector_entry_point="hgym.env:HgymVectorEnv",
                disable_env_checker=False,
            )


register_envs()
