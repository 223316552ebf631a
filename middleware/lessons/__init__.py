"""Video lessons: a video with a WebVTT cue track whose cue bodies are declarative robot commands."""
