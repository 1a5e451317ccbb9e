"""The native vector env (``gymnasium.make_vec("skidnav/SkidSteerNav-v0", num_envs=256)``)
against a ``SyncVectorEnv`` of 256 single envs (``vectorization_mode="sync"``, their infos kept
to the gathered keys), both on the obstacles map, random actions, autoreset by the vector env.
Prints sub-env steps/s (median of three timings) for discrete actions with discrete
observations and for continuous wheel speeds with the feature observation, and the ratio, all
measured in this run on one core (target: >= 200,000 steps/s at N = 256)."""

from __future__ import annotations

import statistics
import time
from typing import Any

import gymnasium

import skidnav  # noqa: F401  (registers the env)
from skidnav.envs.registration import ENV_ID
from skidnav.envs.vector import GatheredInfo

N_ENVS = 256
TARGET = 200_000
REPEATS = 3
CASES = {
    "discrete actions, discrete observation": {},
    "wheel speeds, features (8 rays)": {"action": "continuous", "observation": "features"},
}


def steps_per_second(mode: str, n_steps: int, kwargs: dict[str, Any]) -> float:
    """Sub-env steps/s of ``n_steps`` vector steps of ``mode`` after 5 warm-up steps."""
    wrappers = {"wrappers": [GatheredInfo]} if mode == "sync" else {}
    envs = gymnasium.make_vec(
        ENV_ID, num_envs=N_ENVS, vectorization_mode=mode, map_kind="obstacles", world_seed=0,
        **wrappers, **kwargs,
    )  # fmt: skip
    envs.action_space.seed(1)
    actions = [envs.action_space.sample() for _ in range(n_steps + 5)]
    envs.reset(seed=0)
    for action in actions[:5]:
        envs.step(action)
    start = time.perf_counter()
    for action in actions[5:]:
        envs.step(action)
    return n_steps * N_ENVS / (time.perf_counter() - start)


def native_and_sync(
    kwargs: dict[str, Any], native_steps: int = 400, sync_steps: int = 20
) -> tuple[float, float]:
    """(native, ``SyncVectorEnv``) sub-env steps/s of the case ``kwargs``: the median of
    :data:`REPEATS` timings of :func:`steps_per_second` each, one after the other."""
    native = statistics.median(
        steps_per_second("vector_entry_point", native_steps, kwargs) for _ in range(REPEATS)
    )
    single = statistics.median(steps_per_second("sync", sync_steps, kwargs) for _ in range(REPEATS))
    return native, single


def main() -> None:
    print(f"vector env, {N_ENVS} sub-envs, obstacles map, random actions (target >= {TARGET:,})")
    for name, kwargs in CASES.items():
        native, single = native_and_sync(kwargs)
        print(
            f"  {name:40s} native {native:11,.0f} steps/s; SyncVectorEnv of single envs "
            f"{single:9,.0f} steps/s; ratio {native / single:5.1f} ×",
            flush=True,
        )


if __name__ == "__main__":
    main()
