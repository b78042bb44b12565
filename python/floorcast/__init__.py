"""floorcast in Python: robot exploration of real and generated buildings (simulation, laser
and odometry noise, SLAM, frontiers, layout prediction) as a gymnasium environment, about a
thousand times faster than real time, and policies trained in it run back as strategies in
floorcast's grids, sequential tests and leaderboard (docs/python.md).

    import gymnasium as gym
    import floorcast

    env = gym.make("floorcast/Explore-v0", buildings="buildings/small.toml")
    obs, info = env.reset(seed=1)

Contents: `ExploreEnv` (registered as ``floorcast/Explore-v0``), `VectorExplore` (the native
vector environment; ``gym.make_vec("floorcast/Explore-v0", num_envs=N,
vectorization_mode="vector_entry_point", buildings=...)``), `EnvSpec` (the picklable spec),
`FEATURES`, `CHANNELS`, `default_reward`; `floorcast.serve` runs a policy as a strategy.
"""

import gymnasium as _gym

from . import _native
from ._env import CHANNELS, FEATURES, ExploreEnv, default_reward
from ._spec import EnvSpec
from ._vector import VectorExplore

__version__ = _native.__version__
#: The share of buildings in the test part of the fixed split (``split="test"``).
TEST_SHARE = _native.TEST_SHARE

__all__ = [
    "CHANNELS",
    "FEATURES",
    "EnvSpec",
    "ExploreEnv",
    "TEST_SHARE",
    "VectorExplore",
    "default_reward",
]

if "floorcast/Explore-v0" not in _gym.registry:
    _gym.register(
        id="floorcast/Explore-v0",
        entry_point="floorcast._env:ExploreEnv",
        vector_entry_point="floorcast._vector:VectorExplore",
        disable_env_checker=False,
    )
