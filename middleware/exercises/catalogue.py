"""The exercises the lab ships with (an admin or a tutor adds more through the API); each has a statement, a
template, a scene, a practice start, a region of hidden random starts for submissions, a time limit and a
rubric graded from the robot's ground truth (grading.py). All run in the practice robot's scene, "lab".

A template is stored and graded in English; its comments are said in the reader's language when it is served
(in_language): each comment of the built-in templates is a message of the catalogue (TEMPLATE_COMMENTS), the code
itself stays Python with English names."""

from __future__ import annotations

import io
import textwrap
import tokenize
from collections.abc import Callable
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.translations.robot_words import N_  # titles and statements are shown through the catalogue

TEMPLATE_HEAD = '''from telelab import robot

# The loop runs at 20 Hz: each robot.tick() waits for the next period, sends your last command and reads the
# sensors. It answers False when the time is up or you press Stop.
'''

BUMP_AND_GO = TEMPLATE_HEAD + '''
print("Bump and go: starting")
while robot.tick():
    if robot.front_distance() < 0.45:
        # Something ahead: back off a little, then turn away.
        robot.set_velocity(0.0, 0.0)
    else:
        robot.set_velocity(0.3, 0.0)
'''

WALL_FOLLOWING = TEMPLATE_HEAD + '''
DISTANCE_M = 0.5  # keep the wall on your left at this distance

while robot.tick():
    scan = robot.laser()
    left = scan.nearest(1.2, 1.6)    # beams pointing left
    ahead = scan.nearest(-0.3, 0.3)
    # Your controller here: turn towards or away from the wall to keep `left` near DISTANCE_M.
    robot.set_velocity(0.2, 0.0)
'''

OBSTACLE_AVOIDANCE = TEMPLATE_HEAD + '''import math

GOAL = (3.2, -1.5)  # in the odometry frame, which starts where the robot is placed

while robot.tick():
    pose = robot.odometry()
    dx, dy = GOAL[0] - pose.x_m, GOAL[1] - pose.y_m
    # A virtual force field: an attraction towards the goal, repulsions from the laser's close hits.
    heading = math.atan2(dy, dx) - pose.theta_rad
    robot.set_velocity(0.25, max(-1.0, min(1.0, 1.5 * math.atan2(math.sin(heading), math.cos(heading)))))
'''

COVER_ROOM = TEMPLATE_HEAD + '''
# A vacuum cleaner: sweep as much of the room's floor as you can before the time is up.
while robot.tick():
    robot.set_velocity(0.3, 0.2)
'''

FOLLOW_LINE = TEMPLATE_HEAD + '''
# robot.line() gives the line sensor's five cells, left to right (1 over the tape, 0 on bare floor);
# robot.line_position() is where the tape is under them in metres (left positive), or None when no cell sees it.
while robot.tick():
    offset = robot.line_position()
    if offset is None:
        robot.set_velocity(0.0, 0.0)  # the line is lost: where did you see it last?
    else:
        robot.set_velocity(0.2, 0.0)  # your controller here: turn towards the line
'''

KIDNAPPED = TEMPLATE_HEAD + '''
GOAL = (-3.0, -0.2)  # in the lab's frame

# You were carried somewhere while you were not looking: odometry still believes you are where you were.
# The lab's localization compares the laser with the lab's floor plan:
robot.start_skill("environment_modelling", use_floor_plan=True, restart=True)
robot.start_skill("localization")  # no guess: it searches the whole map
while robot.tick():
    where = robot.localization()
    # Until it has converged, help it see the room (turn on the spot?), then robot.report_pose(x, y) and go to GOAL
    # (robot.run_skill("go_to_goal", goal_x_m=..., goal_y_m=...) steers by the localization).
    robot.set_velocity(0.0, 0.0)
'''

# The lab's line of tape (skill_server/sim/scenes.py LAB_LINE), as the follow-the-line rubric measures it.
LAB_LINE_RUBRIC = {"x_min_m": -1.7, "x_max_m": 1.3, "y_min_m": -0.8, "y_max_m": 0.8, "corner_radius_m": 0.45}

BUILT_IN: list[dict[str, Any]] = [
    {
        "slug": "bump-and-go",
        "title": N_("Bump and go"),
        "statement": N_("Drive around the lab without getting stuck: go straight, and when an obstacle comes close "
                        "(the laser or the bumper tells you), back off, turn to a new direction and go on. Graded from"
                        " where the robot truly went: the distance driven, how many 0.5 m floor cells it visited, and "
                        "the longest time it stayed stuck in one spot."),
        "template": BUMP_AND_GO,
        "scene": "lab",
        "rubric": {"kind": "bump_and_go", "min_travel_m": 6.0, "min_cells": 14, "cell_m": 0.5, "stuck_s": 5.0,
                   "stuck_move_m": 0.1},
        "start": [0.0, 0.0, 0.0],
        "random_starts": {"x_m": [-1.0, 1.0], "y_m": [-0.8, 0.8], "theta_rad": [-3.1, 3.1]},
        "time_limit_s": 45.0,
    },
    {
        "slug": "wall-following",
        "title": N_("Follow the wall at 0.5 m"),
        "statement": N_("The robot starts beside the north wall (y = 3 m), the wall on its left. Follow it, keeping "
                        "its centre 0.5 m from the wall's face, for at least 3 m. Graded from the truth: the RMS error"
                        " of the distance to the wall after the first 5 s, and the distance covered along it."),
        "template": WALL_FOLLOWING,
        "scene": "lab",
        "rubric": {"kind": "wall_following", "x1_m": -4.0, "y1_m": 3.0, "x2_m": 4.0, "y2_m": 3.0,
                   "distance_m": 0.5, "tolerance_m": 0.08, "min_travel_m": 3.0, "settle_s": 5.0},
        "start": [-3.0, 2.45, 0.0],
        "random_starts": {"x_m": [-3.4, -2.4], "y_m": [2.3, 2.6], "theta_rad": [-0.25, 0.25]},
        "time_limit_s": 25.0,
    },
    {
        "slug": "obstacle-avoidance",
        "title": N_("Reach the goal around the pillar"),
        "statement": N_("Drive to the goal 3.7 m ahead of the start (x = 3.2 m, y = -1.5 m in the lab's frame) without"
                        " touching anything: a pillar stands on the straight line. A virtual force field (the goal "
                        "attracts, the laser's close hits repel) is one way. Graded from the truth: the closest the "
                        "robot came to the goal (within 0.4 m for full marks: odometry drifts)."),
        "template": OBSTACLE_AVOIDANCE,
        "scene": "lab",
        "rubric": {"kind": "reach_goal", "x_m": 3.2, "y_m": -1.5, "radius_m": 0.4},
        "start": [-0.5, -1.5, 0.0],
        "random_starts": {"x_m": [-0.7, -0.3], "y_m": [-1.55, -1.45], "theta_rad": [-0.2, 0.2]},
        "time_limit_s": 40.0,
    },
    {
        "slug": "cover-room",
        "title": N_("Vacuum the open floor"),
        "statement": N_("Sweep the open floor in the middle of the lab (x from -1.5 to 1.5 m, y from -1 to 1 m) like a"
                        " robot vacuum cleaner. Graded from the truth: the share of that floor the robot's body passed"
                        " over (60% for full marks)."),
        "template": COVER_ROOM,
        "scene": "lab",
        "rubric": {"kind": "cover_room", "x_min_m": -1.5, "x_max_m": 1.5, "y_min_m": -1.0, "y_max_m": 1.0,
                   "cell_m": 0.25, "min_coverage": 0.6},
        "start": [0.0, 0.0, 0.0],
        "random_starts": {"x_m": [-0.5, 0.5], "y_m": [-0.5, 0.5], "theta_rad": [-3.1, 3.1]},
        "time_limit_s": 60.0,
    },
    {
        "slug": "follow-line",
        "title": N_("Follow the line"),
        "statement": N_("A loop of black tape, 8.4 m long, is stuck on the lab's floor (a 3 m x 1.6 m rectangle with "
                        "rounded corners around the middle). The robot starts on it, facing along it. Follow it "
                        "anticlockwise with the line sensor under the robot's front (robot.line(), "
                        "robot.line_position()) for one whole lap. Graded from where the robot truly went: the share "
                        "of the line its centre passed within 8 cm of (85% for full marks) and the time its centre "
                        "spent farther than that from the line (at most 3 s)."),
        "template": FOLLOW_LINE,
        "scene": "lab",
        "rubric": {"kind": "follow_line", **LAB_LINE_RUBRIC, "tolerance_m": 0.08, "min_covered": 0.85,
                   "max_off_s": 3.0},
        "start": [-0.6, -0.8, 0.0],
        "random_starts": {"x_m": [-1.1, 0.2], "y_m": [-0.83, -0.77], "theta_rad": [-0.2, 0.2]},
        "time_limit_s": 50.0,
    },
    {
        "slug": "kidnapped",
        "title": N_("Localize after a kidnapping"),
        "statement": N_("The robot is carried to a place you do not know, facing you do not know where, and nobody "
                        "tells it: its odometry still believes it stands where it was. Find out where it is with the "
                        "lab's localization (robot.start_skill(\"localization\") compares the laser with the lab's "
                        "floor plan; robot.localization() reads its estimate), tell the grader with "
                        "robot.report_pose(x, y), then drive to the goal at x = -3 m, y = -0.2 m. Graded from the "
                        "truth: the distance between the pose you reported and where the robot truly was then (within "
                        "0.3 m for full marks), and the closest the robot came to the goal after that (within 0.3 m)."),
        "template": KIDNAPPED,
        "scene": "lab",
        "rubric": {"kind": "kidnapped", "tolerance_m": 0.3, "x_m": -3.0, "y_m": -0.2, "radius_m": 0.3},
        "start": [2.9, -0.2, 2.5],
        "random_starts": {"x_m": [2.5, 3.4], "y_m": [-0.7, 0.5], "theta_rad": [-3.1, 3.1]},
        "time_limit_s": 120.0,
    },
]

# Every comment of the templates above, as in_language looks it up: a comment's lines joined by single spaces.
# tests/unit/exercises/test_template_comments.py checks that the two agree.
TEMPLATE_COMMENTS = (
    N_("The loop runs at 20 Hz: each robot.tick() waits for the next period, sends your last command and reads the "
       "sensors. It answers False when the time is up or you press Stop."),
    N_("Something ahead: back off a little, then turn away."),
    N_("keep the wall on your left at this distance"),
    N_("beams pointing left"),
    N_("Your controller here: turn towards or away from the wall to keep `left` near DISTANCE_M."),
    N_("in the odometry frame, which starts where the robot is placed"),
    N_("A virtual force field: an attraction towards the goal, repulsions from the laser's close hits."),
    N_("A vacuum cleaner: sweep as much of the room's floor as you can before the time is up."),
    N_("robot.line() gives the line sensor's five cells, left to right (1 over the tape, 0 on bare floor); "
       "robot.line_position() is where the tape is under them in metres (left positive), or None when no cell sees "
       "it."),
    N_("the line is lost: where did you see it last?"),
    N_("your controller here: turn towards the line"),
    N_("in the lab's frame"),
    N_("You were carried somewhere while you were not looking: odometry still believes you are where you were. The "
       "lab's localization compares the laser with the lab's floor plan:"),
    N_("no guess: it searches the whole map"),
    N_("Until it has converged, help it see the room (turn on the spot?), then robot.report_pose(x, y) and go to GOAL "
       "(robot.run_skill(\"go_to_goal\", goal_x_m=..., goal_y_m=...) steers by the localization)."),
)
_TEMPLATE_WIDTH = 116  # the templates' longest line: a translated comment is wrapped within it


def comments(code: str) -> list[tuple[int, int, int, str]]:
    """code's comments as (first line, last line, column, text): a comment's consecutive lines at one column are one
    comment, their texts joined by spaces; a comment after code on its line is its own. [] for code that does not
    tokenize (a student's unfinished program)."""
    found: list[tuple[int, int, int, str]] = []
    lines = code.splitlines()
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(code).readline))
    except (tokenize.TokenError, SyntaxError):
        return []
    for token in tokens:
        if token.type != tokenize.COMMENT:
            continue
        row, column = token.start
        text = token.string.removeprefix("#").strip()
        alone = not lines[row - 1][:column].strip()
        if found and alone and found[-1][1] == row - 1 and found[-1][2] == column \
                and not lines[row - 2][:column].strip():
            first, _, _, before = found[-1]
            found[-1] = (first, row, column, f"{before} {text}")
        else:
            found.append((row, row, column, text))
    return found


def in_language(code: str, translate: Callable[[str], str] = gettext) -> str:
    """code with each comment the catalogue knows said in the reader's language (translate: gettext, whose language
    is the request's); everything else, and a comment it does not know, as it is."""
    lines = code.splitlines()
    for first, last, column, text in reversed(comments(code)):
        said = str(translate(text)) if text in TEMPLATE_COMMENTS else text
        if said == text:
            continue
        head = lines[first - 1][:column]
        if head.strip():  # after code: the comment stays on its line
            lines[first - 1] = f"{head}# {said}"
            continue
        width = max(_TEMPLATE_WIDTH - column - 2, 40)
        lines[first - 1:last] = [f"{head}# {part}" for part in textwrap.wrap(said, width)]
    return "\n".join(lines) + ("\n" if code.endswith("\n") else "")
