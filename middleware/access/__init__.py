"""Round-robin access to each robot: one controller at a time, turns when others wait, observers."""
