"""The BARN benchmark on the runner: its worlds, rules and score as a study (docs/barn.md,
"Running the benchmark")."""
