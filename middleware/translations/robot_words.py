"""The words a robot sends for people to read (its panels' and skills' titles and help, in English, from the skill
server) and those of the panels the middleware adds (middleware/lab/panels.py), marked here so that `make
translations` puts them in the catalogue; i18n.translate_panels reads each descriptor's words through it.

A robot that says new words: add them here (the catalogue test lists none of them; a word missing here shows in
English, nothing breaks)."""

from __future__ import annotations


def N_(text: str) -> str:  # noqa: N802 (gettext's name for "mark for translation, translate later")
    return text


ROBOT_WORDS = (
    N_("Line sensor"),
    N_("Reflectance cells under the robot's front, left to right: 1 over the tape, 0 on bare floor. Shown in scenes "
       "with a line of tape."),
    N_("Camera"),
    N_("What the robot sees: its camera's video, or the view your browser draws from its pose."),
    N_("Odometry"),
    N_("Position, heading and speeds integrated from the wheels."),
    N_("Lab model"),
    N_("The lab seen from above: the robot, its readings, the map; click to set a goal."),
    N_("3D lab view"),
    N_("The lab in 3D, drawn by your browser: the robot at its odometry pose, its laser hits and sonar cones, the "
       "goal and the path planned to it, the map on the floor. Drag to turn it."),
    N_("Sonar"),
    N_("The ring of sonars, nearest echo each."),
    N_("Laser"),
    N_("The 180-degree laser scan ahead."),
    N_("Room camera"),
    N_("The robot seen from a camera on the room's wall, drawn by your browser where the robot truly stands. Pan, "
       "tilt and zoom it with the buttons, the arrow keys, + and -, or by dragging."),
    N_("Low-level commands"),
    N_("The battery, the velocity ceilings and the watchdog timeout."),
    N_("Direct control"),
    N_("Drive the base with linear and angular velocities. Send commands continuously: the base stops when they stop "
       "arriving for the deadman timeout. Activated as a goal, it holds the velocities for duration_s and then "
       "stops."),
    N_("As a goal: how long to hold the velocities before stopping (Drive commands ignore it)."),
    N_("Detect obstacle"),
    N_("Watches the laser and sonars and announces an obstacle whenever something comes closer to the robot's rim "
       "than the warning distance (a plan reacts with on obstacle_detected). Runs beside any motor skill; go-to-goal "
       "uses the same obstacle data to plan around what it sees."),
    N_("Wall following"),
    N_("Follow a wall or any contour on one side using the sonars, keeping a set distance between the robot's rim "
       "and the contour; turns at inner corners, goes round outer corners and bridges short gaps."),
    N_("Round trip"),
    N_("Complex skill: go to a point (go-to-goal), come back to where the robot started (go-to-goal) and turn back "
       "to the start heading (orientation control)."),
    N_("Environment modelling"),
    N_("Perceptive skill: builds an occupancy grid of the lab from the laser (and near sonar echoes) while the robot "
       "moves. Each scan is placed at the pose the robot believes (the localization estimate when localization runs, "
       "else odometry), corrected by matching the scan to the map built so far. Drive a tour (one lap of wall "
       "following) for a whole map. The floor-plan option is a teaching aid: it draws the lab as built first. The "
       "map is kept after the skill ends; GetMap returns it."),
    N_("Orientation control"),
    N_("Turn on the spot to a heading of the lab frame and stop within the tolerance."),
    N_("Go to goal"),
    N_("Drive to a point of the lab, going around the obstacles the laser and sonars detect on the way. Ends when "
       "the robot is within the maximum error of the goal; deactivating reports the distance left."),
    N_("Localization"),
    N_("Perceptive skill: estimates the robot's pose against the environment model with a particle filter (sets of "
       "poses whose laser readings best match the map), starting from a guess. While it runs, the motor skills steer "
       "by its estimate instead of raw odometry. Needs a map (Environment modelling). If the guess is wrong or "
       "unknown, it searches the whole map with the scans of a turn or a short drive."),
    N_("Motor skill: acts on the wheels from the command alone."),
    N_("Perceptive skill: interprets the sensors for the other skills."),
    N_("Sensorimotor skill: chooses the wheels' commands from what it perceives."),
    N_("Deliberative skill: reasons over time (plans, builds the map)."),
    N_("Your personal practice robot: only you see it, so you control it whenever you are here."),
    N_("Who controls the robot and who waits."),
    N_("Drive"),
    N_("Direct control: arrow keys, the pad or a gamepad."),
    N_("Turn"),
    N_("Your personal practice robot: nobody else reads this chat; notes to yourself."),
    N_("Talk with the others connected to this robot."),
    N_("Chat"),
    N_("Response times"),
    N_("Round trips: browser to middleware, and middleware to the robot."),
    # The skills' parameters: their labels (client_ui/static/lib/parameters.js makes them from the names) and help.
    N_("Duration"),
    N_("Warning distance"),
    N_("Distance"),
    N_("Side"),
    N_("Speed"),
    N_("Goal x"),
    N_("Goal y"),
    N_("Max error"),
    N_("Heading tolerance"),
    N_("Timeout"),
    N_("Use sonar"),
    N_("Restart"),
    N_("Use floor plan"),
    N_("Align scans"),
    N_("Heading"),
    N_("Tolerance"),
    N_("Max angular"),
    N_("Initial x"),
    N_("Initial y"),
    N_("Initial theta"),
    N_("Initial spread"),
    N_("Particle count"),
    N_("Announce an obstacle closer than this to the robot's rim."),
    N_("Stop watching after this much time (0 = until cancelled)."),
    N_("Distance to keep between the robot's rim and the contour."),
    N_("Which side the contour is on."),
    N_("Forward speed on straight runs."),
    N_("Stop and succeed after this long (0 = until cancelled)."),
    N_("Turning point x in the lab frame."),
    N_("Turning point y in the lab frame."),
    N_("Cruising speed."),
    N_("Position tolerance at the turning point and back at the start."),
    N_("Heading tolerance back at the start."),
    N_("Abort with TIMEOUT after this much time per step."),
    N_("Also mark near sonar echoes (behind the laser's half-plane)."),
    N_("Start from an empty map instead of extending the one kept."),
    N_("Teaching aid: start from the lab's floor plan (walls and furniture as built), then add readings."),
    N_("Correct the pose by matching each scan to the map built so far before adding it (SLAM-lite), so the map does "
       "not inherit odometry drift."),
    N_("Target heading, counter-clockwise from the lab's +x axis."),
    N_("The heading counts as reached within this error."),
    N_("Fastest turn rate."),
    N_("Abort with TIMEOUT after this much time."),
    N_("Goal x in the lab frame (the start pose's frame)."),
    N_("Goal y in the lab frame."),
    N_("Cruising speed; the robot slows near obstacles and the goal."),
    N_("The goal counts as reached within this distance."),
    N_("Guess of x."),
    N_("Guess of y."),
    N_("Guess of the heading."),
    N_("How far off the guess may be (standard deviation of the first particles)."),
    N_("How far off the heading guess may be."),
    N_("Number of particles."),
    # The robot's stream states, shown as they come (middleware/robots/fanout.py).
    N_("connecting"),
    N_("live"),
    N_("The robot is not answering; reconnecting."),
    # The graders' fixed feedback, stored in English with each result (middleware/assessment/grading.py).
    N_("No answer."),
    N_("Correct."),
    N_("The answer is not one of the choices."),
    N_("The answer is not a set of choices."),
    N_("The answer names a choice that does not exist."),
    N_("The answer is not a number."),
    # The experimental task's grader (middleware/assessment/trace_grading.py); those with values: i18n._WITH_VALUES.
    N_("Nothing was recorded: the robot did not report during the attempt."),
    N_("No pose was reported."),
    N_("No obstacle zone was marked."),
    # The skills' help as the skill server words it now.
    N_("Perceptive skill: watches the laser and sonars and announces an obstacle whenever something comes closer to "
       "the robot's rim than the warning distance. Runs beside any motor skill; go-to-goal uses the same obstacle "
       "data to plan around what it sees."),
    N_("Deliberative skill: builds an occupancy grid of the lab from the laser (and near sonar echoes) while the "
       "robot moves. Each scan is placed at the pose the robot believes (the localization estimate when localization "
       "runs, else odometry), corrected by matching the scan to the map built so far. Drive a tour (one lap of wall "
       "following) for a whole map. The floor-plan option is a teaching aid: it draws the lab as built first. The "
       "map is kept after the skill ends; GetMap returns it."),
)
