"""The chat room of each robot: persisted messages, a per-user rate limit, moderation by tutors."""
