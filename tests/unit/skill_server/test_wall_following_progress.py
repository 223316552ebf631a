"""Wall following's progress: a timed run reports the share of its time followed; an open-ended one none."""

from __future__ import annotations

import pytest
from skill_sim_helpers import TOKEN

from skill_server.sequencer import attach_sequencer
from skill_server.sim.geometry import Pose2D
from skill_server.sim.world import World


@pytest.mark.parametrize(("duration_s", "expected"), [(8.0, 0.5), (0.0, 0.0)])
def test_progress_is_the_share_of_a_timed_run(duration_s: float, expected: float) -> None:
    with World("lab", seed=1, realtime=False, deadman_timeout_s=1000.0) as world:
        sequencer = attach_sequencer(world)
        world.set_controller(TOKEN)
        world.set_pose(Pose2D(-1.0, -1.4, 0.0))
        goal_id = sequencer.activate(TOKEN, "wall_following", {"side": "right", "duration_s": duration_s},
                                     preempt=True).goal.goal_id
        world.step_for(4.0)
        running = sequencer.goals.get(goal_id)
        assert running is not None and not running.status.is_terminal
        assert running.snapshot().feedback.progress == pytest.approx(expected, abs=0.05)
