"""Per-user preferences, such as the layout of the lab console."""
