"""The one line of help of each top-level ``skidnav`` verb and group, in one place: the verb's
module passes it to argparse, and :func:`skidnav.cli.listing_parser` lists them for
``skidnav --help`` without importing any command module (which would import numba, pandas and
the rest: seconds instead of a fraction of one)."""

from __future__ import annotations

HELP = {
    "run": "run an experiment or study config (agents × maps × presets × seeds); resumable",
    "report": "write one self-contained HTML report of a results directory",
    "tune": "tune the agents' hyperparameters on tuning maps (Optuna); resumable",
    "study": "questions asked of the runner: shortcuts that write a study config and run it",
    "world": "maps, one simulated episode, floor presets, the BARN worlds",
    "robot": "run agents in real time on a robot or sim server",
    "camera": "overhead-camera calibration and tracking",
}
"""Top-level verb or group → its line of help (``skidnav --help``)."""
