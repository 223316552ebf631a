"""The robot tier: one gRPC skill server per robot, running a pybullet world."""
