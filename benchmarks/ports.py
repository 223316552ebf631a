"""Ports for the servers a benchmark or a test starts by number (`telelab up --port`, `telelab web --port`).

A port probed with bind(0) and closed again is taken from the kernel's ephemeral range, where any server bound to
port 0 or any outgoing connection may be given it before the lab binds it, seconds later: a `telelab up` then
failed to bind while its health check was answered by whichever server had the port. A port below that range is
handed out by nobody else, so only another free_port could pick it, at random among thousands.
"""

from __future__ import annotations

import random
import socket
from pathlib import Path

_EPHEMERAL_RANGE = Path("/proc/sys/net/ipv4/ip_local_port_range")
_LOWEST = 10_000
_CHOICE = random.SystemRandom()  # not the seeded module random: test processes reseed it alike


def free_port(neighbours: int = 1) -> int:
    """A TCP port on 127.0.0.1 nobody listens on now, outside the ephemeral range, with the next neighbours - 1
    ports free too (`telelab up` puts its demo LMS on the next port)."""
    low, high = _below_ephemeral()
    for _ in range(200):
        port = _CHOICE.randrange(low, high - neighbours)
        if all(_bindable(port + offset) for offset in range(neighbours)):
            return port
    raise RuntimeError(f"no free TCP port between {low} and {high} after 200 tries")


def _below_ephemeral() -> tuple[int, int]:
    try:
        first = int(_EPHEMERAL_RANGE.read_text().split()[0])
    except (OSError, ValueError, IndexError):
        first = 32_768
    return (_LOWEST, first) if first - _LOWEST > 1_000 else (first - 1_000, first)


def _bindable(port: int) -> bool:
    with socket.socket() as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True
