"""The one seeding convention (seeding.py): named children of a root seed, the experiment's spawn
tree, the arena's streams and ``skidnav world simulate``'s separate env and policy streams."""

import csv

import numpy as np

from skidnav.cli import main
from skidnav.experiments.config import AgentSpec, ExperimentConfig, MapSpec
from skidnav.experiments.runs import expand_runs
from skidnav.realtime.arena import seed_streams
from skidnav.seeding import (
    ARENA_ROLES,
    ROOT_ROLES,
    RUN_ROLES,
    WORLD_ROLES,
    SeedKey,
    child_sequences,
    seed_int,
    streams,
)


def state(sequence: np.random.SeedSequence) -> list[int]:
    return sequence.generate_state(4).tolist()


def test_children_are_the_spawned_sequences_in_role_order() -> None:
    for roles in (ROOT_ROLES, WORLD_ROLES, RUN_ROLES, ARENA_ROLES):
        spawned = np.random.SeedSequence(11).spawn(len(roles))
        children = child_sequences(11, roles)
        assert list(children) == list(roles)
        assert [state(c) for c in children.values()] == [state(s) for s in spawned]
    parent = np.random.SeedSequence(11).spawn(3)[2]
    nested = child_sequences(parent, WORLD_ROLES)
    expected = np.random.SeedSequence(11).spawn(3)[2].spawn(4)
    assert [state(c) for c in nested.values()] == [state(s) for s in expected]
    again = child_sequences(SeedKey.of(parent).sequence(), WORLD_ROLES)
    assert [state(c) for c in again.values()] == [state(c) for c in nested.values()]


def test_streams_of_distinct_roles_differ_and_repeat() -> None:
    first, second = streams(4, ARENA_ROLES), streams(4, ARENA_ROLES)
    draws = {role: tuple(g.integers(0, 2**62, 4)) for role, g in first.items()}
    assert len(set(draws.values())) == len(ARENA_ROLES)
    assert all(tuple(second[r].integers(0, 2**62, 4)) == d for r, d in draws.items())
    arena = seed_streams(4)
    assert {r: tuple(g.integers(0, 2**62, 4)) for r, g in arena.items()} == draws


def test_the_experiment_spawn_tree_is_unchanged() -> None:
    config = ExperimentConfig(
        "x",
        (AgentSpec("q-learning", "Q"), AgentSpec("dyna-q", "D")),
        (MapSpec("free", "free"),),
        seeds=3,
        root_seed=21,
    )
    world_root, run_root = np.random.SeedSequence(21).spawn(2)
    worlds, runs = world_root.spawn(3), run_root.spawn(6)
    for spec in expand_runs(config):
        assert spec.world_seed == SeedKey.of(worlds[spec.seed])
        assert spec.run_seed == SeedKey.of(runs[spec.index])
    assert seed_int(worlds[0]) < 2**63


def test_simulate_draws_its_policy_and_env_noise_from_separate_children(tmp_path) -> None:
    table = tmp_path / "t.csv"
    arguments = ["world", "simulate", "--map-kind", "free", "--random", "30", "--seed", "6"]
    assert main([*arguments, "--out", str(tmp_path / "t.png"), "--csv", str(table)]) == 0
    with table.open() as handle:
        actions = [int(row["action"]) for row in csv.DictReader(handle)][1:]
    policy = np.random.default_rng(child_sequences(6, ARENA_ROLES)["agent"])
    assert actions == [int(policy.integers(4)) for _ in actions]
    shared = np.random.default_rng(6)  # the old convention: one stream for env and policy
    assert actions != [int(shared.integers(4)) for _ in actions]
