"""The simulated robot: the world loop, the robot model, scenes and sensors (no grpc, no protos)."""
