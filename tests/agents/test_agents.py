"""The classic tabular agents: equivalences, learning on the Dyna Maze, registry, save/load."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from skidnav.agents.greedy import greedy_rollout
from skidnav.agents.tabular.config import DynaQConfig
from skidnav.agents.tabular.registry import available_agents, load_agent, make_agent
from skidnav.agents.training import train_agent
from skidnav.envs.mazes import dyna_maze
from skidnav.errors import CorruptFileError, UserError

CLASSIC = ("q-learning", "dyna-q", "dyna-q-plus", "prioritized-sweeping")
BOOK = {"alpha": 0.1, "gamma": 0.95, "epsilon": 0.1}


def trained(name: str, episodes: int, seed: int = 0, **options: object):  # type: ignore[no-untyped-def]
    env = dyna_maze()
    agent = make_agent(name, 54, 4, {**BOOK, **options}, np.random.default_rng(seed))
    log = train_agent(agent, env, episodes, seed=seed)
    return agent, log


def test_dyna_q_without_planning_is_q_learning() -> None:
    q_learning, log_q = trained("q-learning", 15)
    dyna, log_d = trained("dyna-q", 15, planning_steps=0)
    assert np.array_equal(q_learning.q, dyna.q)
    assert np.array_equal(log_q.lengths, log_d.lengths)
    assert dyna.planning_updates == 0 and dyna.model.n_pairs > 0


OPTIMISTIC = {"initial_q": 1.0}  # above every true value: unvisited pairs get tried


@pytest.mark.parametrize(
    ("name", "options", "episodes"),
    [
        ("q-learning", {"alpha": 0.5, **OPTIMISTIC}, 120),
        ("dyna-q", {"planning_steps": 20, **OPTIMISTIC}, 30),
        (
            "dyna-q",
            {"planning_steps": 20, "planning_mode": "sample", "alpha": 0.5, **OPTIMISTIC},
            30,
        ),
        ("dyna-q", {"planning_steps": 20, "planning_mode": "expected", **OPTIMISTIC}, 30),
        ("dyna-q-plus", {"planning_steps": 20, "kappa": 1e-4, "alpha": 0.5}, 30),
        ("prioritized-sweeping", {"planning_steps": 20, "alpha": 0.5, **OPTIMISTIC}, 30),
    ],
)
def test_each_agent_finds_the_shortest_dyna_maze_path(
    name: str, options: dict[str, object], episodes: int
) -> None:
    agent, log = trained(name, episodes, seed=3, **options)
    assert greedy_rollout(agent, dyna_maze(), 100) == 14
    assert log.successes.all()
    assert log.lengths[-5:].mean() < 30  # ε = 0.1 costs a few steps on average


def test_prioritized_sweeping_converges_to_value_iteration_on_its_model() -> None:
    agent, _ = trained("prioritized-sweeping", 10, seed=1, alpha=1.0, planning_steps=50, theta=0.0)
    while agent.queue.size[0] > 0:  # finish the sweep
        agent.observe(0, 0, 0.0, 0, False)
    model = agent.model
    values = np.zeros_like(agent.q)
    for _ in range(200):
        for state, action in (divmod(int(key), 4) for key in model.visited_pairs()):
            out = model.outcomes(state, action)
            continuation = 1.0 - out.termination[0]
            bootstrap = 0.95 * continuation * values[out.next_states[0]].max()
            values[state, action] = out.mean_rewards[0] + bootstrap
    assert np.allclose(agent.q, values, atol=1e-9)


def test_planning_speeds_up_learning() -> None:
    lengths = {
        n: np.mean(
            [trained("dyna-q", 10, seed, planning_steps=n)[1].lengths[1:10] for seed in range(3)]
        )
        for n in (0, 10)
    }
    assert lengths[10] * 4 < lengths[0]


def test_registry_lists_the_classic_agents_and_rejects_bad_input() -> None:
    assert set(CLASSIC) <= set(available_agents())
    with pytest.raises(UserError, match="unknown agent"):
        make_agent("sarsa", 4, 2)
    with pytest.raises(UserError, match="planning_step"):
        make_agent("dyna-q", 4, 2, {"planning_step": 3})
    with pytest.raises(UserError, match="alpha"):
        make_agent("q-learning", 4, 2, {"alpha": 0.0})
    with pytest.raises(ValueError, match="planning_mode"):
        DynaQConfig(planning_mode="best")
    with pytest.raises(UserError):
        make_agent("dyna-q-plus", 4, 2, DynaQConfig())  # wrong config class


def test_epsilon_decays_per_episode() -> None:
    agent = make_agent(
        "q-learning", 4, 2, {"epsilon": 0.8, "epsilon_decay": 0.5, "epsilon_min": 0.1}
    )
    values = []
    for _ in range(4):
        values.append(agent.epsilon)
        agent.end_episode()
    assert values == [0.8, 0.4, 0.2, 0.1]


@pytest.mark.parametrize("name", CLASSIC)
def test_save_load_then_continue_gives_identical_numbers(name: str, tmp_path: Path) -> None:
    options = {} if name == "q-learning" else {"planning_steps": 5}
    agent, _ = trained(name, 4, seed=1, **options)
    agent.save(tmp_path / "agent")
    env = dyna_maze()
    env.reset(seed=9)
    train_agent(agent, env, 3)
    loaded = load_agent(tmp_path / "agent.npz")
    assert type(loaded) is type(agent) and loaded.config == agent.config
    env = dyna_maze()
    env.reset(seed=9)
    train_agent(loaded, env, 3)
    assert np.array_equal(loaded.q, agent.q)
    assert loaded.planning_updates == agent.planning_updates
    assert (loaded.steps, loaded.episodes) == (agent.steps, agent.episodes)
    assert loaded.rng.random() == agent.rng.random()


def test_corrupt_or_missing_files_raise_one_line_errors(tmp_path: Path) -> None:
    agent, _ = trained("dyna-q", 2, planning_steps=2)
    npz_path, json_path = agent.save(tmp_path / "a")
    data = npz_path.read_bytes()
    npz_path.write_bytes(data[: len(data) // 2])
    with pytest.raises(CorruptFileError) as truncated:
        load_agent(tmp_path / "a")
    assert "\n" not in str(truncated.value)
    npz_path.write_bytes(data)
    json_path.write_text(json_path.read_text().replace('"n_states": 54', '"n_states": 50'))
    with pytest.raises(CorruptFileError, match="shape"):
        load_agent(tmp_path / "a")
    json_path.write_text("{not json")
    with pytest.raises(CorruptFileError):
        load_agent(tmp_path / "a")
    with pytest.raises(CorruptFileError):
        load_agent(tmp_path / "missing")


def test_damaged_archives_and_json_name_the_file(tmp_path: Path) -> None:
    agent, _ = trained("dyna-q", 2, planning_steps=2)
    npz_path, json_path = agent.save(tmp_path / "a")
    data, meta = npz_path.read_bytes(), json_path.read_text()
    # Flipped bytes anywhere in the compressed archive: bad deflate streams (zlib.error), bad CRCs,
    # a bad compression-method field (NotImplementedError), damaged headers; some land in fields
    # nobody reads and the agent loads.
    failures = 0
    for offset in range(0, len(data), 7):
        damaged = bytearray(data)
        damaged[offset] ^= 0xFF
        npz_path.write_bytes(bytes(damaged))
        try:
            load_agent(tmp_path / "a")
        except CorruptFileError as error:
            assert str(error).startswith(str(npz_path)) and "\n" not in str(error)
            failures += 1
    assert failures > len(data) // 14
    npz_path.write_bytes(data)
    for not_an_object in ("[]", "null", "42", '"agent"'):
        json_path.write_text(not_an_object)
        with pytest.raises(CorruptFileError, match=f"^{json_path}: .*JSON object"):
            load_agent(tmp_path / "a")
    json_path.write_text(meta.replace('"steps": ', '"steps": -'))
    with pytest.raises(CorruptFileError, match="counter steps"):
        load_agent(tmp_path / "a")
    json_path.write_text(meta)
    arrays = dict(np.load(npz_path))
    np.savez_compressed(npz_path, **{**arrays, "q": arrays["q"].astype(np.float32)})
    with pytest.raises(CorruptFileError, match=r"float32 of shape \(54, 4\), expected float64"):
        load_agent(tmp_path / "a")
    del arrays["model.pair_key"]
    np.savez_compressed(npz_path, **arrays)
    with pytest.raises(
        CorruptFileError, match=f"^{npz_path}: .*missing model array 'model.pair_key'"
    ):
        load_agent(tmp_path / "a")


@pytest.mark.parametrize(
    ("name", "array", "change", "problem"),
    [
        ("dyna-q-plus", "visited_states", lambda v: np.append(v, v[0]), "visited states repeat"),
        ("dyna-q-plus", "last_tried", lambda v: v + 10**6, "last_tried"),
        # state 11 is the wall cell (1, 2): never the start of a transition
        ("prioritized-sweeping", "queue_items", lambda v: np.r_[11 * 4, v[1:]], "never observed"),
        ("dyna-q", "model.entry_sibling", np.zeros_like, "model arrays"),
        ("dyna-q", "model.pair_key", lambda v: v + 54 * 4, "outside the Q table"),
    ],
)
def test_inconsistent_state_arrays_are_rejected(
    name: str, array: str, change: object, problem: str, tmp_path: Path
) -> None:
    agent, _ = trained(name, 3, seed=1, planning_steps=5)
    npz_path, _ = agent.save(tmp_path / "a")
    with np.load(npz_path) as archive:
        arrays = {key: archive[key] for key in archive.files}
    assert arrays[array].size > 0
    arrays[array] = change(arrays[array])  # type: ignore[operator]
    np.savez_compressed(npz_path, **arrays)
    with pytest.raises(CorruptFileError, match=problem):
        load_agent(tmp_path / "a")


def test_memory_of_dyna_q_model_on_a_large_state_space() -> None:
    n_states = 360_000
    agent = make_agent("dyna-q", n_states, 4, {"planning_steps": 1}, np.random.default_rng(0))
    rng = np.random.default_rng(1)
    state = 0
    # Neighbouring moves on a 600 × 600 grid: a realistic spread of visited pairs.
    moves = np.array([1, -1, 600, -600])
    for action in rng.integers(0, 4, 100_000).tolist():
        next_state = int(np.clip(state + moves[action], 0, n_states - 1))
        agent.model.observe(state, action, -1.0, next_state, False)
        state = next_state
    model_bytes = agent.model.nbytes
    assert agent.model.n_outcomes <= 100_000
    assert model_bytes < 20e6  # dense p(s'|s,a) would need n_states² · 4 · 8 bytes ≈ 4 TB
