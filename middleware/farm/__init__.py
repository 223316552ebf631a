"""The robot farm: where simulated robots run (local child processes, or actors on a Ray cluster)."""
