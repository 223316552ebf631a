"""Tours: fully guided demonstrations on a practice robot, and live guided classes on a lab robot."""
