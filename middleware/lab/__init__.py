"""The lab: robot list, console page, robot API and the robot WebSocket channels."""
