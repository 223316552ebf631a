"""Reference solutions of the catalogue's exercises (each should earn full marks from any hidden start) and wrong
ones (each should earn little): a rubric that cannot fail shows up as a wrong solution passing."""

from __future__ import annotations

HEAD = "from telelab import robot\nimport math\n"

BUMP_AND_GO = HEAD + '''
turn_until = 0.0
direction = 1.0
backing_until = 0.0
count = 0
while robot.tick():
    t = robot.time()
    if t < backing_until:
        robot.set_velocity(-0.15, 0.0)
    elif t < turn_until:
        robot.set_velocity(0.0, 1.2 * direction)
    elif robot.bumper() or robot.front_distance(0.6) < 0.55:
        count += 1
        direction = 1.0 if count % 3 else -1.0
        backing_until = t + 0.6
        turn_until = backing_until + 0.8 + 0.3 * (count % 3)
        print("obstacle", count, "at", round(t, 1), "s")
    else:
        robot.set_velocity(0.45, 0.0)
'''

BUMP_AND_GO_WRONG = HEAD + '''
while robot.tick():
    robot.set_velocity(0.45, 0.0)   # never looks: drives into the first wall and stays there
'''

WALL_FOLLOWING = HEAD + '''
DISTANCE_M = 0.5
while robot.tick():
    scan = robot.laser()
    # The wall's distance and angle from the left-hand beams: the nearest hit on the left side.
    left = scan.nearest(0.9, 1.6)
    ahead = scan.nearest(-0.3, 0.3)
    error = left - DISTANCE_M
    if ahead < 0.7:
        robot.set_velocity(0.1, -1.0)
    else:
        robot.set_velocity(0.22, max(-0.8, min(0.8, 2.5 * error)))
'''

WALL_FOLLOWING_WRONG = HEAD + '''
while robot.tick():
    robot.set_velocity(0.3, -0.35)   # drives off in a curve, away from the wall
'''

OBSTACLE_AVOIDANCE = HEAD + '''
# Seek the goal; when something blocks the way, turn left until the way is clear and drive on a little
# (the goal's frame is the lab's: the odometry starts where the robot was placed).
GOAL = (3.2, -1.5)
avoid_until = 0.0
turning = False
while robot.tick():
    pose = robot.odometry()
    dx, dy = GOAL[0] - pose.x_m, GOAL[1] - pose.y_m
    if math.hypot(dx, dy) < 0.05:
        robot.stop()
        continue
    if turning:
        if robot.front_distance(0.7) > 1.0:
            turning, avoid_until = False, robot.time() + 1.6
        else:
            robot.set_velocity(0.0, 1.0)
            continue
    if robot.front_distance(0.5) < 0.6:
        turning = True
        robot.set_velocity(0.0, 1.0)
        continue
    if robot.time() < avoid_until:
        robot.set_velocity(0.3, 0.0)
        continue
    bearing = math.atan2(dy, dx) - pose.theta_rad
    bearing = math.atan2(math.sin(bearing), math.cos(bearing))
    robot.set_velocity(0.3 * max(0.0, math.cos(bearing)), max(-1.4, min(1.4, 2.0 * bearing)))
'''

OBSTACLE_AVOIDANCE_WRONG = HEAD + '''
while robot.tick():
    pose = robot.odometry()
    bearing = math.atan2(-1.5 - pose.y_m, 3.2 - pose.x_m) - pose.theta_rad
    robot.set_velocity(0.35, max(-1.4, min(1.4, 2.0 * math.atan2(math.sin(bearing), math.cos(bearing)))))
'''

COVER_ROOM = HEAD + '''
# Boustrophedon: lanes along x, 0.35 m apart, inside the region the rubric measures.
lanes = [-0.85 + 0.34 * k for k in range(6)]
targets = []
for k, y in enumerate(lanes):
    xs = (-1.3, 1.3) if k % 2 == 0 else (1.3, -1.3)
    targets += [(xs[0], y), (xs[1], y)]
index = 0
while robot.tick() and index < len(targets):
    pose = robot.odometry()
    tx, ty = targets[index]
    dx, dy = tx - pose.x_m, ty - pose.y_m
    if math.hypot(dx, dy) < 0.12:
        index += 1
        continue
    bearing = math.atan2(dy, dx) - pose.theta_rad
    bearing = math.atan2(math.sin(bearing), math.cos(bearing))
    robot.set_velocity(0.45 * max(0.0, math.cos(bearing)) ** 2, max(-1.5, min(1.5, 2.5 * bearing)))
robot.stop()
robot.tick()
'''

COVER_ROOM_WRONG = HEAD + '''
while robot.tick():
    robot.set_velocity(0.1, 1.0)   # circles on the spot
'''

FOLLOW_LINE = HEAD + '''
# Steer towards the tape under the sensor (proportional), slower when it is far off the middle; when it is lost
# (a corner), turn on the spot towards the side it was last seen on. Gentle gains: the browser reads the sensor at
# 10 Hz, some 0.1 s late.
last = 0.0
while robot.tick():
    offset = robot.line_position()
    if offset is None:
        robot.set_velocity(0.0, 1.0 if last >= 0 else -1.0)
        continue
    last = offset
    robot.set_velocity(0.25 - 2.5 * abs(offset), max(-1.5, min(1.5, 18.0 * offset)))
'''

FOLLOW_LINE_WRONG = HEAD + '''
while robot.tick():
    robot.set_velocity(0.3, 0.0)   # never reads the sensor: drives straight off the line at the first corner
    if robot.time() > 15:
        break
'''

KIDNAPPED = HEAD + '''
GOAL = (-3.0, -0.2)
# The lab's localization against its floor plan, with no guess: it searches the whole map with the scans of a turn.
print("modelling:", robot.start_skill("environment_modelling", use_floor_plan=True, restart=True))
print("localization:", robot.start_skill("localization"))
where = None
while robot.tick():
    where = robot.localization()
    if where is not None and where.converged and where.std_m < 0.1:
        break
    robot.set_velocity(0.0, 0.6)
robot.stop()
robot.sleep(0.5)
where = robot.localization()
robot.report_pose(where.x_m, where.y_m)
print("localized at", round(where.x_m, 2), round(where.y_m, 2), "after", round(robot.time(), 1), "s")
# Drive to the goal steering by the localization's estimate (it keeps running); the way west is open.
while robot.tick():
    where = robot.localization()
    dx, dy = GOAL[0] - where.x_m, GOAL[1] - where.y_m
    if math.hypot(dx, dy) < 0.1:
        break
    bearing = math.atan2(dy, dx) - where.theta_rad
    bearing = math.atan2(math.sin(bearing), math.cos(bearing))
    robot.set_velocity(0.35 * max(0.0, math.cos(bearing)) ** 2, max(-1.2, min(1.2, 2.0 * bearing)))
robot.stop()
robot.tick()
print("at the goal after", round(robot.time(), 1), "s")
'''

KIDNAPPED_WRONG = HEAD + '''
# Trusts odometry, which still believes the robot is where it was before it was carried off.
pose = robot.odometry()
robot.report_pose(pose.x_m, pose.y_m)
robot.run_skill("go_to_goal", goal_x_m=-3.0, goal_y_m=-0.2, max_error_m=0.1)
'''
