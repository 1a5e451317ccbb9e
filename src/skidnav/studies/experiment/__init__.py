"""The plain experiment (agents × maps × presets × seeds, docs/experiments.md) as a study of the
one runner: ``kind = "experiment"``, the kind of every config that names none.

* :mod:`~skidnav.studies.experiment.study` — ``STUDY``: the grid of an experiment config
  (:mod:`skidnav.experiments.configfile`), the runner's trial
  (:mod:`skidnav.experiments.trial`) and the experiment report, with the sections studies add to
  it (:data:`skidnav.studies.kind.EXPERIMENT_SECTIONS`) and its one-line verdict.
"""
