"""The results directory: one atomic file per finished run, tidy tables, metadata.

Layout of a results directory::

    config.json          resolved config + fingerprint (a resume must match it) + layout kind
    config.toml          the config file as given (when run from a file)
    runs/run-000042.npz  one finished run: episode arrays, final trajectory, maps, summary JSON,
                         the code that produced it (version, commit, dirty flag, session)
    runs/run-000042/     with ``[experiment] save_agents``: its trained agent (agent.npz,
                         agent.json, by the family's own save) and the world it was trained
                         for (world.json, map.txt), written before the run file
    episodes.parquet     tidy: one row per (run, episode)
    summaries.parquet    one row per run: grid coordinates + every metric (also summaries.csv)
    metadata.json        config, package versions, git commit, seeds, every session (start,
                         code, runs done)

    .skidnav.lock        held (``flock``) by the process writing here, its pid inside

Every file is written to a temporary name, synced and moved into place with ``os.replace``
(:func:`skidnav.files.atomic.write_atomic`), so a run is either completely there or absent: after a
kill, the runs already written are skipped and the rest are run again (none lost, none
duplicated), and reopening removes the temporaries of writers that died. A write that fails (a
full disk) is one line naming the file (:func:`skidnav.files.atomic.writing`): the files before
it stay whole, so the same command resumes once there is room. One process at a time writes a
directory (:func:`~skidnav.experiments.lock.directory_lock`). The tidy tables are read back as
saved files too (:func:`~skidnav.experiments.tables.read_table`). Run files are read as
:class:`~skidnav.files.saved.SavedArchive` with the arrays and sizes the config allows; nothing is
pickled.

What a run file holds depends on the kind of grid, described by a :class:`RunLayout`: an
experiment's (:data:`EXPERIMENT_LAYOUT`, the default) or a study's (e.g. the
hardware-in-the-loop study's :data:`skidnav.studies.hardware.study.STUDY_LAYOUT`: real-time
episodes, no maps). ``config.json`` names the kind (:func:`results_kind`), so a directory of one
kind is never read as another.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from skidnav.errors import CorruptFileError, UserError, shown
from skidnav.experiments.config import (
    ExperimentConfig,
    config_from_dict,
    config_to_dict,
)
from skidnav.experiments.limits import MAX_STEPS
from skidnav.experiments.runs import Grid
from skidnav.experiments.tables import read_table
from skidnav.files.atomic import (
    remove_stale_temporaries,
    write_atomic,
    write_npz_atomic,
    write_user_file,
    writing,
)
from skidnav.files.saved import ArraySpec, SavedArchive, parse_json, read_json, up_to
from skidnav.world.grid import MAX_SIZE

EPISODE_COLUMNS = (
    "return",
    "length",
    "success",
    "collisions",
    "planning_updates",
    "wall_time",
    "greedy_length",
    "greedy_success",
    "greedy_cost",
)
LATER_EPISODE_COLUMNS = ("greedy_cost",)
"""Episode columns that run files written before them lack: such a file reads them as NaN (not
measured), and its summary lacks the columns added with them (``oracle_cost``,
``oracle_rollout_cost``), NaN in the tables."""
GRID_COLUMNS = ("run_id", "agent", "algorithm", "map", "preset", "seed")


NO_FILES: Mapping[str, bytes] = {}
"""The files of a run that keeps none (read only; a plain dict, so that a result crosses to the
runner's process: a ``MappingProxyType`` cannot be pickled)."""


class TrialResult(NamedTuple):
    """What one run sends back to the runner (picklable: plain arrays, dicts and strings).

    Attributes:
        run_id: ``RunSpec.run_id``.
        coordinates: grid coordinates (``RunSpec.coordinates``): agent (label), algorithm, map,
            preset, seed.
        episodes: per-episode arrays, keys the layout's ``episode_columns`` (an experiment's:
            :data:`EPISODE_COLUMNS`), each shape (N,).
        summary: per-run metrics (an experiment's:
            :func:`skidnav.experiments.metrics.run_metrics`).
        arrays: the layout's other arrays; an experiment's: ``greedy_poses`` (T, 3)
            [m, m, rad]; on the skid-steer env also
            ``value_map`` (n_x, n_y) max of Q over headings and actions, ``heading_map``
            (n_x, n_y) heading bin of that maximum, ``policy_map`` (n_x, n_y) greedy action at
            the start heading, ``start_heading`` () [rad], ``occupancy`` (n_x, n_y) bool,
            ``start`` and ``goal`` (2,), ``slip_eta`` (regions_x, regions_y) [rad/s]. Cells
            without a learned value (walls, never updated) are NaN / −1 (see
            :func:`skidnav.experiments.value_maps.value_maps`).
        files: files kept beside the run file, ``runs/<run_id>/<name>``, by name: the trained
            agent of a config with ``save_agents`` (:func:`skidnav.experiments.trial.agent_files`);
            empty otherwise.
    """

    run_id: str
    coordinates: dict[str, Any]
    episodes: dict[str, np.ndarray]
    summary: dict[str, float]
    arrays: dict[str, np.ndarray]
    files: Mapping[str, bytes] = NO_FILES


_WORLD_ARRAYS = {
    "value_map": "f", "heading_map": "i", "policy_map": "i", "occupancy": "b", "slip_eta": "f",
}  # fmt: skip
"""The (n_x, n_y) or (regions_x, regions_y) arrays of a skid-steer run, by dtype kind."""


DOCUMENT_SPEC = ArraySpec((), kinds="U")
"""The ``document`` member of every run file: coordinates, summary and code record as JSON."""


def run_file_specs(config: ExperimentConfig) -> dict[str, ArraySpec]:
    """What a run file of ``config`` may hold besides its document (:class:`TrialResult`): every
    episode column (at most ``episodes`` long), the greedy poses (at most one per action plus
    the start) and, on the skid-steer env, the maps (at most the largest map's cells)."""
    episodes = up_to(config.episodes)
    poses = up_to((config.max_steps or MAX_STEPS) + 1)
    cells = up_to(MAX_SIZE)
    specs = {}
    for key in EPISODE_COLUMNS:
        specs[f"episode.{key}"] = ArraySpec((episodes,), kinds="fiub")
    specs["array.greedy_poses"] = ArraySpec((poses, 3), "<f8")
    for key, kind in _WORLD_ARRAYS.items():
        specs[f"array.{key}"] = ArraySpec((cells, cells), kinds=kind)
    specs["array.start_heading"] = ArraySpec((), "<f8")
    specs["array.start"] = specs["array.goal"] = ArraySpec((2,), kinds="i")
    return specs


OPTIONAL_ARRAYS = frozenset(
    f"array.{key}" for key in (*_WORLD_ARRAYS, "start_heading", "start", "goal")
) | {f"episode.{key}" for key in LATER_EPISODE_COLUMNS}
"""Members of a run file only a skid-steer run has, and the episode columns older run files lack
(:data:`LATER_EPISODE_COLUMNS`)."""


@dataclass(frozen=True)
class RunLayout:
    """What the results directory of one kind of grid holds, and how its grid is saved.

    Attributes:
        kind: the kind's name, written in ``config.json``.
        episode_columns: the per-episode arrays of every run, in table order.
        to_dict: the grid as a JSON-ready dict (saved in ``config.json`` and ``metadata.json``).
        from_dict: the grid back from that dict (ValueError, TypeError or KeyError if invalid).
        file_specs: what a run file of a grid may hold besides its document (checked before
            anything is read).
        optional: members of ``file_specs`` a run file may lack (an episode column among them
            reads as NaN).
    """

    kind: str
    episode_columns: tuple[str, ...]
    to_dict: Callable[[Any], dict[str, Any]]
    from_dict: Callable[[dict[str, Any]], Any]
    file_specs: Callable[[Any], dict[str, ArraySpec]]
    optional: frozenset[str] = frozenset()


EXPERIMENT_LAYOUT = RunLayout(
    "experiment", EPISODE_COLUMNS, config_to_dict, config_from_dict, run_file_specs, OPTIONAL_ARRAYS
)
"""The layout of ``skidnav run``'s results (an :class:`ExperimentConfig` grid)."""


class ResultStore:
    """A results directory bound to one config (see module docs), of the kind ``layout``."""

    def __init__(self, root: Path | str, layout: RunLayout = EXPERIMENT_LAYOUT) -> None:
        self.root = Path(root)
        self.runs_dir = self.root / "runs"
        self.layout = layout
        self._specs: dict[str, ArraySpec] | None = None

    def check(self, config: Grid) -> bool:
        """True if the directory already holds results of ``config``, False if it holds none
        (it may not exist yet); creates nothing.

        Raises:
            UserError: the directory holds results of a different config or another kind.
        """
        if self.root.exists() and not self.root.is_dir():
            raise UserError(f"{self.root}: not a directory; choose another --out")
        config_path = self.root / "config.json"
        if not config_path.exists():
            return False
        document = self._read_document(config_path)
        if document.get("fingerprint") != config.fingerprint():
            raise UserError(
                f"{self.root}: holds results of a different config; choose another --out"
            )
        return True

    @classmethod
    def open(
        cls,
        root: Path | str,
        config: Grid,
        source_text: str = "",
        layout: RunLayout = EXPERIMENT_LAYOUT,
    ) -> ResultStore:
        """Create the directory for ``config`` or reopen it to resume the same config.

        Raises:
            UserError: the directory holds results of a different config or another kind.
        """
        store = cls(root, layout)
        exists = store.check(config)
        with writing(store.runs_dir, "runs directory"):
            store.runs_dir.mkdir(parents=True, exist_ok=True)
        for directory in (store.root, store.runs_dir):
            remove_stale_temporaries(directory)
        if exists:
            return store
        config_path = store.root / "config.json"
        document = {
            "kind": layout.kind,
            "fingerprint": config.fingerprint(),
            "config": layout.to_dict(config),
        }
        write_user_file(config_path, json.dumps(document, indent=2).encode(), "config")
        if source_text:
            write_user_file(store.root / "config.toml", source_text.encode(), "config")
        return store

    def _read_json(self, path: Path) -> dict[str, Any]:
        if not path.is_file():
            raise UserError(f"{path}: missing; is {self.root} a results directory?")
        return read_json(path, allow_nonfinite=True)

    def _read_document(self, path: Path) -> dict[str, Any]:
        """``config.json``, refused unless it is of this store's kind (one written before
        kinds were recorded is an experiment's)."""
        document = self._read_json(path)
        kind = document.get("kind", EXPERIMENT_LAYOUT.kind)
        if kind != self.layout.kind:
            raise UserError(
                f"{self.root}: holds {shown(kind)} results, not {self.layout.kind!r} results"
            )
        return document

    def config(self) -> Any:
        """The config (grid) these results belong to: an :class:`ExperimentConfig` for the
        default layout."""
        document = self._read_document(self.root / "config.json")
        try:
            return self.layout.from_dict(document["config"])
        except (KeyError, TypeError, ValueError) as error:
            raise CorruptFileError(
                f"{self.root / 'config.json'}: invalid config ({error})"
            ) from None

    def run_path(self, run_id: str) -> Path:
        """Where the run file of ``run_id`` lives."""
        return self.runs_dir / f"{run_id}.npz"

    def finished(self) -> set[str]:
        """Ids of the runs already written."""
        return {path.stem for path in self.runs_dir.glob("run-*.npz")}

    def run_folder(self, run_id: str) -> Path:
        """Where the files kept beside the run file of ``run_id`` live (:attr:`TrialResult.files`:
        ``agent.npz``, ``agent.json``, ``world.json``, ``map.txt``)."""
        return self.runs_dir / run_id

    def write_run(self, result: TrialResult, code: dict[str, Any] | None = None) -> None:
        """Store one finished run atomically, with the record ``code`` of the code that produced
        it (:mod:`skidnav.experiments.sessions`). Its files (:attr:`TrialResult.files`) are
        written first, each atomically: a run whose run file exists has them all, and a run
        killed before its run file is run again and writes them again."""
        if result.files:
            folder = self.run_folder(result.run_id)
            with writing(folder, "agent folder"):
                folder.mkdir(exist_ok=True)
            remove_stale_temporaries(folder)
            for name, data in result.files.items():
                path = folder / name
                with writing(path, "agent file"):
                    write_atomic(path, data)
        payload: dict[str, np.ndarray] = {
            f"episode.{key}": np.asarray(value) for key, value in result.episodes.items()
        }
        payload.update({f"array.{key}": np.asarray(v) for key, v in result.arrays.items()})
        document = {
            "coordinates": result.coordinates,
            "summary": result.summary,
            "code": code or {},
        }
        payload["document"] = np.array(json.dumps(document))
        path = self.run_path(result.run_id)
        with writing(path, "run file"):
            write_npz_atomic(path, payload, compress=True)

    def _run_specs(self) -> dict[str, ArraySpec]:
        if self._specs is None:
            self._specs = {"document": DOCUMENT_SPEC, **self.layout.file_specs(self.config())}
        return self._specs

    def read_run(self, run_id: str) -> TrialResult:
        """Load one run file (CorruptFileError naming it when damaged or too large)."""
        path = self.run_path(run_id)
        with SavedArchive(path) as archive:
            arrays = archive.read_all(self._run_specs(), self.layout.optional)
        document = _run_document(path, arrays.pop("document"))
        episodes = {k.split(".", 1)[1]: v for k, v in arrays.items() if k.startswith("episode.")}
        others = {k.split(".", 1)[1]: v for k, v in arrays.items() if k.startswith("array.")}
        episodes = _with_missing_columns(episodes, self.layout.episode_columns)
        return TrialResult(run_id, document["coordinates"], episodes, document["summary"], others)

    def run_code(self, run_id: str) -> dict[str, Any]:
        """The record of the code that produced run ``run_id`` (empty if it was not recorded)."""
        path = self.run_path(run_id)
        specs = self._run_specs()
        with SavedArchive(path) as archive:
            archive.check_names(specs, self.layout.optional)
            document = _run_document(path, archive.read("document", specs["document"]))
        code = document.get("code", {})
        return code if isinstance(code, dict) else {}

    def iter_runs(self, run_ids: Iterable[str] | None = None) -> Iterable[TrialResult]:
        """Every finished run (or the given ones), in id order."""
        for run_id in sorted(self.finished() if run_ids is None else run_ids):
            yield self.read_run(run_id)

    def consolidate(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        """Write ``episodes.parquet``, ``summaries.parquet`` and ``summaries.csv`` from the run
        files; returns (episodes, summaries)."""
        episode_frames, summary_rows = [], []
        for result in self.iter_runs():
            columns = self.layout.episode_columns
            frame = pd.DataFrame({key: result.episodes[key] for key in columns})
            frame.insert(0, "episode", np.arange(1, len(frame) + 1))
            for position, key in enumerate(GRID_COLUMNS):
                value = result.run_id if key == "run_id" else result.coordinates[key]
                frame.insert(position, key, value)
            episode_frames.append(frame)
            summary_rows.append({"run_id": result.run_id, **result.coordinates, **result.summary})
        if not summary_rows:
            raise UserError(f"{self.root}: no finished runs")
        episodes = pd.concat(episode_frames, ignore_index=True)
        summaries = pd.DataFrame(summary_rows)
        for name, frame in (("episodes", episodes), ("summaries", summaries)):
            write_user_file(self.root / f"{name}.parquet", frame.to_parquet(index=False), "table")
        write_user_file(
            self.root / "summaries.csv", summaries.to_csv(index=False).encode(), "table"
        )
        return episodes, summaries

    def load_tables(self) -> tuple[pd.DataFrame, pd.DataFrame]:
        """(episodes, summaries) from the Parquet files (consolidating first if missing)."""
        paths = [self.root / "episodes.parquet", self.root / "summaries.parquet"]
        if not all(path.exists() for path in paths):
            return self.consolidate()
        return read_table(paths[0]), read_table(paths[1])

    def write_metadata(self, metadata: dict[str, Any]) -> None:
        """Write ``metadata.json`` atomically."""
        text = json.dumps(metadata, indent=2, default=str)
        write_user_file(self.root / "metadata.json", text.encode(), "metadata")

    def metadata(self) -> dict[str, Any]:
        """``metadata.json`` (empty when missing)."""
        path = self.root / "metadata.json"
        return self._read_json(path) if path.exists() else {}


def results_kind(root: Path | str) -> str:
    """The kind of the results in ``root``, as its ``config.json`` names it (a
    :attr:`RunLayout.kind`: ``"experiment"``, or a study's); ``"experiment"`` when the directory
    has no ``config.json`` (reading it then names what is missing) or one written before kinds
    were recorded.

    Raises:
        UserError: ``config.json`` cannot be read.
        CorruptFileError: ``config.json`` is damaged, or its kind is not a string.
    """
    path = Path(root) / "config.json"
    if not path.exists():
        return EXPERIMENT_LAYOUT.kind
    kind = read_json(path, allow_nonfinite=True).get("kind", EXPERIMENT_LAYOUT.kind)
    if not isinstance(kind, str):
        raise CorruptFileError(f"{path}: kind: expected a string, got {shown(kind)}")
    return kind


def _with_missing_columns(
    episodes: dict[str, np.ndarray], columns: tuple[str, ...]
) -> dict[str, np.ndarray]:
    """``episodes`` in the order of ``columns``, those a run file lacks (optional members only:
    written before they existed) filled with NaN, each as long as the others."""
    n_episodes = len(next(iter(episodes.values()), ()))
    missing = np.full(n_episodes, np.nan)
    return {key: episodes[key] if key in episodes else missing.copy() for key in columns}


def _run_document(path: Path, text: np.ndarray) -> dict[str, Any]:
    """The summary document of a run file: coordinates, summary and code record (NaN and inf
    are legitimate summary values)."""
    document = parse_json(str(text[()]), path, allow_nonfinite=True)
    for key, kind in (("coordinates", dict), ("summary", dict)):
        if not isinstance(document.get(key), kind):
            raise CorruptFileError(f"{path}: run document without {key!r}")
    return document
