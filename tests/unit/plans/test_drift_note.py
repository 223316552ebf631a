"""A run beside a lab robot whose odometry drifted says why its run on the lab robot will differ, and the ways back
(issue 34, item 11)."""

from __future__ import annotations


def test_a_start_beside_a_drifted_robot_says_why_its_run_differs_and_the_ways_back() -> None:
    from middleware.plans.runs import LabRobotNow, drift_note

    assert drift_note(LabRobotNow("lab-1", "lab", None, 0.05)) == ""
    note = drift_note(LabRobotNow("lab-1", "lab", None, 1.04))
    assert "odometry is 1.0 m off where it stands" in note and "localize it" in note and "dock" in note

