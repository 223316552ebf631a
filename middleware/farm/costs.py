"""What one simulated robot costs, measured, and how many a host holds from its cores and memory.

The figures are measured by `telelab bench --only farm` (the robots-per-core scenario): a headless robot in
the lab scene, stepping in real time with nobody watching. Placement on Ray declares them as the robot's
resources, and the local farm divides the host by them.
"""

from __future__ import annotations

import os
from pathlib import Path

# Measured by benchmarks/farm.py on the 2-core development machine (its record in benchmarks/results/): an idle
# headless robot used 4.6-4.8 % of a core and 96 MB (its skill server), 238 MB as a Ray actor with it. Rounded up.
HEADLESS_ROBOT_CPU_SHARE = 0.05
ROBOT_MEMORY_MB = 100
RAY_ROBOT_MEMORY_MB = 250
# Left to the web tier, the database and the operating system on a host that also runs robots.
HOST_RESERVE_CPU_SHARE = 0.2
HOST_RESERVE_MEMORY_FRACTION = 0.2


def host_cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0))


def available_memory_mb(meminfo: Path = Path("/proc/meminfo")) -> float:
    """MemAvailable of this host, in MB."""
    for line in meminfo.read_text().splitlines():
        if line.startswith("MemAvailable:"):
            return int(line.split()[1]) / 1024
    raise OSError("MemAvailable is missing from /proc/meminfo")


def robots_per_host(cores: float, memory_mb: float) -> int:
    """How many headless robots a host of cores and memory_mb runs at real time, with its reserve left."""
    by_cpu = (cores * (1 - HOST_RESERVE_CPU_SHARE)) / HEADLESS_ROBOT_CPU_SHARE
    by_memory = memory_mb * (1 - HOST_RESERVE_MEMORY_FRACTION) / ROBOT_MEMORY_MB
    return max(0, int(min(by_cpu, by_memory)))
