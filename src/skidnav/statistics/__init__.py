"""Statistics: intervals over seeds, survival of runs, numbers for people."""
