"""The CMA-ES policy search (docs/agents/cmaes.md) as a study run by ``skidnav run``
(``kind = "policy-search"``): :mod:`.grid` (the config: slip presets × seeds), :mod:`.trial`
(one search per run), :mod:`.export` (a run's policy file and learning curve), :mod:`.report`
(the report section), :mod:`.study` (``STUDY``)."""
