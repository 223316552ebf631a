"""What one simulated robot costs, measured, and how many a host holds from its cores and memory.

The figures are measured by `telelab bench --only farm` (the robots-per-core scenario): a headless robot in
the lab scene, stepping in real time, driven and watched as a student's console does. Placement on Ray declares
them as the robot's resources, and the local farm divides the host by them.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path

from middleware.config import ConfigError

# Measured by benchmarks/farm.py on the 2-core development machine (its records in benchmarks/results/): a headless
# robot driven and watched through its 30 Hz pose stream used 5.5-6.5 % of a core and 99 MB (its skill server),
# 247 MB as a Ray actor with it; parked (nobody using it) 0.3-0.8 %. The farm plans for robots in use. On a host
# about 30 % slower the same robot used 6.0-7.6 %: the figure is the host's, measured before sizing one.
HEADLESS_ROBOT_CPU_SHARE = 0.06
# A lab whose robot hosts measure otherwise (benchmarks/farm.py on one of them) declares its own figure.
CPU_SHARE_VARIABLE = "TELELAB_ROBOT_CPU_SHARE"
CPU_SHARE_RANGE = (0.005, 1.0)
ROBOT_MEMORY_MB = 100
RAY_ROBOT_MEMORY_MB = 250
# Left to the web tier, the database and the operating system on a host that also runs robots.
HOST_RESERVE_CPU_SHARE = 0.2
HOST_RESERVE_MEMORY_FRACTION = 0.2


def robot_cpu_share(environ: Mapping[str, str] | None = None) -> float:
    """The share of a core a robot in use is planned at: TELELAB_ROBOT_CPU_SHARE, else the development machine's
    figure; ConfigError names the setting when it is not a share of a core."""
    raw = (os.environ if environ is None else environ).get(CPU_SHARE_VARIABLE, "").strip()
    if not raw:
        return HEADLESS_ROBOT_CPU_SHARE
    low, high = CPU_SHARE_RANGE
    try:
        share = float(raw)
    except ValueError:
        raise ConfigError(f"{CPU_SHARE_VARIABLE} must be a robot's share of a core, such as 0.07, not {raw!r}.") \
            from None
    if not low <= share <= high:  # NaN fails both comparisons
        raise ConfigError(f"{CPU_SHARE_VARIABLE} must be between {low:g} and {high:g} of a core, not {raw!r}.")
    return share


def host_cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0))


def available_memory_mb(meminfo: Path = Path("/proc/meminfo")) -> float:
    """MemAvailable of this host, in MB."""
    for line in meminfo.read_text().splitlines():
        if line.startswith("MemAvailable:"):
            return int(line.split()[1]) / 1024
    raise OSError("MemAvailable is missing from /proc/meminfo")


def robots_per_host(cores: float, memory_mb: float, reserve: bool = True,
                    cpu_share: float = HEADLESS_ROBOT_CPU_SHARE) -> int:
    """How many headless robots in use, each planned at cpu_share of a core, a host of cores and memory_mb runs at
    real time, with its reserve left for the web tier (not on a Ray robot host, whose CPUs the operator declares to
    Ray)."""
    usable_cores = cores * (1 - HOST_RESERVE_CPU_SHARE) if reserve else cores
    usable_mb = memory_mb * (1 - HOST_RESERVE_MEMORY_FRACTION) if reserve else memory_mb
    by_cpu = usable_cores / cpu_share
    by_memory = usable_mb / ROBOT_MEMORY_MB
    return max(0, int(min(by_cpu, by_memory)))
