"""The bridge to the robots: one gRPC link per robot, streams fanned out to every viewer."""
