"""The share of a core a robot is planned at is the robot hosts' own (TELELAB_ROBOT_CPU_SHARE): on a host about 30 %
slower than the development machine a robot used 6.0-7.6 % of a core where the default plans 6 %."""

from __future__ import annotations

import pytest

from middleware.config import ConfigError
from middleware.farm.costs import HEADLESS_ROBOT_CPU_SHARE, robot_cpu_share, robots_per_host
from middleware.farm.local import LocalProcessFarm
from middleware.farm.setup import build_farm


def test_without_the_setting_the_development_machine_s_figure_is_used() -> None:
    assert robot_cpu_share({}) == HEADLESS_ROBOT_CPU_SHARE
    assert robot_cpu_share({"TELELAB_ROBOT_CPU_SHARE": "  "}) == HEADLESS_ROBOT_CPU_SHARE


def test_a_declared_share_sizes_the_hosts() -> None:
    assert robot_cpu_share({"TELELAB_ROBOT_CPU_SHARE": "0.08"}) == 0.08
    # 16 cores, 80 % of them for robots: 213 at 6 %, 160 at 8 %; memory is not the bound here.
    assert robots_per_host(16, 10**6) == 213
    assert robots_per_host(16, 10**6, cpu_share=0.08) == 160
    assert LocalProcessFarm(cpu_share=0.5).capacity().robots < LocalProcessFarm(cpu_share=0.05).capacity().robots


@pytest.mark.parametrize("raw", ["fast", "0", "-0.1", "1.5", "nan", "inf", "6%"])
def test_a_setting_that_is_no_share_of_a_core_is_refused_at_start_naming_it(raw: str) -> None:
    with pytest.raises(ConfigError, match="TELELAB_ROBOT_CPU_SHARE"):
        robot_cpu_share({"TELELAB_ROBOT_CPU_SHARE": raw})
    with pytest.raises(ConfigError, match="TELELAB_ROBOT_CPU_SHARE"):
        build_farm({"TELELAB_FARM": "ray", "TELELAB_RAY_ADDRESS": "127.0.0.1:6379", "TELELAB_ROBOT_CPU_SHARE": raw})
