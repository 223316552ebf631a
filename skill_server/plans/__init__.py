"""Plans run on the skill server: the plan as received (model), its checks (validation), the controllers of its
own lines (steps) and the executor that runs it as one motor goal (executor)."""
