"""The teleoperation-under-delay experiment (thesis chapter 4): injected delay, trials, the class's results."""
