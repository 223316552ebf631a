"""The real-time channels' runtime: every WebSocket of a process served on one asyncio loop, no thread each."""
