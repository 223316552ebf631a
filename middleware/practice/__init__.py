"""Personal practice robots: one simulated robot (its own skill server process) per learner who asks."""
