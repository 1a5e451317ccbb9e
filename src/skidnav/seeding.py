"""The one seeding convention: a root seed, spawned into child streams with fixed roles.

Every random number of the platform comes from a :class:`numpy.random.SeedSequence` root (an
integer seed) spawned with ``SeedSequence.spawn``; child ``k`` of a root always has the role at
position ``k`` of a role tuple below, so adding a role at the end changes no existing stream.
Two consumers never share a stream (architecture.md, "Randomness").

* :data:`ROOT_ROLES` — an experiment's ``root_seed``: the *world* root (spawned once per
  (map, preset, seed) world), the *run* root (spawned once per run of the grid) and the tuning
  root of ``skidnav tune``.
* :data:`WORLD_ROLES` — one world of an experiment: map generation, slip field, evaluation
  episode seeds (spawned once per rollout), the oracle's sampling.
* :data:`RUN_ROLES` — one run of an experiment: the agent, the training episodes (the env's
  ``reset`` seed).
* :data:`ARENA_ROLES` — the integer seed of one world outside an experiment (a real-time run, the
  sim server, ``skidnav world simulate``): map, slip field, the simulated robot (slip draws, noise,
  dropped poses; the env's ``reset`` seed in ``skidnav world simulate``), the agent or random
  policy. The env's ``world_seed`` uses the first two, so the env and the sim server given one
  seed build the same map and floor.
* :data:`TRAINING_ROLES` — the integer seed of one agent trained from Python (:mod:`skidnav.api`):
  the agent and the training episodes (as :data:`RUN_ROLES`), and the evaluation rollouts' seeds
  (spawned once per rollout).
* :data:`GENERALISATION_ROLES` — the root seed of ``skidnav study generalise``: the training
  worlds and the held-out worlds (each spawned once per world), the runs (spawned once per seed,
  each with :data:`RUN_ROLES`) and the evaluation rollouts' seeds (the same for every agent and
  run).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

ROOT_ROLES = ("world", "run", "tuning")
"""Children of an experiment's ``SeedSequence(root_seed)``."""
WORLD_ROLES = ("map", "slip", "evaluation", "oracle")
"""Children of one experiment world's stream."""
RUN_ROLES = ("agent", "episodes")
"""Children of one experiment run's stream."""
ARENA_ROLES = ("map", "slip", "robot", "agent")
"""Children of the integer seed of one world outside an experiment."""
GENERALISATION_ROLES = ("training", "held-out", "run", "evaluation")
"""Children of the root seed of a generalisation study."""
TRAINING_ROLES = ("agent", "episodes", "evaluation")
"""Children of the integer seed of one agent trained from Python (:mod:`skidnav.api`)."""

Seed = int | np.random.SeedSequence


def child_sequences(seed: Seed, roles: Sequence[str]) -> dict[str, np.random.SeedSequence]:
    """The children of ``seed`` (an integer root or a SeedSequence), named by ``roles``.

    Child ``k`` is ``SeedSequence(seed).spawn(len(roles))[k]`` for an integer; for a sequence the
    children are built from its spawn key, so asking twice gives the same children.

    >>> a, b = child_sequences(7, RUN_ROLES).values()
    >>> a.spawn_key, b.spawn_key
    ((0,), (1,))
    """
    return {role: child(seed, k) for k, role in enumerate(roles)}


def child(seed: Seed, k: int) -> np.random.SeedSequence:
    """Child ``k`` of ``seed`` (an integer root or a SeedSequence), ``SeedSequence(seed).spawn(
    k + 1)[k]`` for an integer, built from the spawn key so that asking twice gives the same."""
    root = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    return np.random.SeedSequence(root.entropy, spawn_key=(*root.spawn_key, k))


def streams(seed: Seed, roles: Sequence[str]) -> dict[str, np.random.Generator]:
    """Independent generators named by ``roles``, one per child of ``seed``."""
    return {role: np.random.default_rng(s) for role, s in child_sequences(seed, roles).items()}


def seed_int(sequence: np.random.SeedSequence) -> int:
    """A 63-bit integer seed drawn from ``sequence`` (for APIs that take an int seed).

    >>> seed_int(np.random.SeedSequence(7)) == seed_int(np.random.SeedSequence(7))
    True
    """
    return int(sequence.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))


@dataclass(frozen=True)
class SeedKey:
    """A SeedSequence as plain integers (JSON- and pickle-friendly)."""

    entropy: int
    spawn_key: tuple[int, ...]

    def sequence(self) -> np.random.SeedSequence:
        """The SeedSequence these integers name."""
        return np.random.SeedSequence(self.entropy, spawn_key=self.spawn_key)

    @classmethod
    def of(cls, sequence: np.random.SeedSequence) -> SeedKey:
        """The integers naming ``sequence``."""
        entropy = sequence.entropy
        assert isinstance(entropy, int)
        return cls(entropy, tuple(int(k) for k in sequence.spawn_key))
