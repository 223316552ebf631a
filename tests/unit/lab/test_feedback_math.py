"""The feedback layer's pure maths (client_ui/static/lib/feedback-math.js), run in headless Chromium."""

from __future__ import annotations

import math

import pytest

pytestmark = pytest.mark.e2e

IMPORT = "const m = await import('/lib/feedback-math.js');"


def run(page, body: str):
    """Evaluates body (which may use `m`, the module) in the page and returns its value."""
    return page.evaluate(f"async () => {{ {IMPORT} {body} }}")


def held(seconds: float, linear: float, angular: float, start_seq: int = 1) -> str:
    """JS for a list of 20 Hz commands held for seconds, starting at t=0."""
    count = round(seconds * 20)
    return (f"Array.from({{length: {count}}}, (_, i) => ({{sequence: {start_seq} + i, sentMs: i * 50, "
            f"linear_mps: {linear}, angular_radps: {angular}}}))")


def test_a_turn_shifts_the_picture_sideways_by_the_angle_through_the_field_of_view(module_page) -> None:
    result = run(module_page, f"""
        const camera = m.cameraModel({{width: 320, height: 240, hfovDeg: 60}});
        const motion = {{maxAngularAccelRadps2: 1e9, maxLinearAccelMps2: 1e9}};
        const pose = m.integrateCommands({held(0.5, 0, 1.0)}, 500, null, motion);
        const t = m.warpTransform(pose, camera);
        return {{theta: pose.theta_rad, x: pose.x_m, shift: t.shiftX, scale: t.scale, f: camera.f}};
    """)
    # Equation 1: ten 20 Hz inputs of 1 rad/s turn 10 * 1/20 = 0.5 rad.
    assert result["theta"] == pytest.approx(0.5, abs=1e-6)
    assert result["x"] == pytest.approx(0.0, abs=1e-9)
    # Turning left (positive) moves the picture right, by f * tan(angle), about angle / hfov of the width.
    assert result["shift"] == pytest.approx(result["f"] * math.tan(0.5), rel=1e-6)
    assert 0.4 * 320 < result["shift"] < 0.6 * 320
    assert result["scale"] == pytest.approx(1.0, abs=1e-6)


def test_a_right_turn_shifts_left_and_a_full_half_turn_leaves_nothing_known(module_page) -> None:
    result = run(module_page, """
        const camera = m.cameraModel({});
        const right = m.warpTransform({x_m: 0, y_m: 0, theta_rad: -0.2}, camera);
        const back = m.warpTransform({x_m: 0, y_m: 0, theta_rad: Math.PI}, camera);
        return {right: right.shiftX, backVisible: back.visible, backShift: Math.abs(back.shiftX)};
    """)
    assert result["right"] < 0
    assert result["backVisible"] is False and result["backShift"] >= 320


def test_forward_motion_scales_up_about_the_vanishing_point_and_backward_scales_down(module_page) -> None:
    result = run(module_page, """
        const camera = m.cameraModel({});
        const fwd = m.warpTransform({x_m: 0.5, y_m: 0, theta_rad: 0}, camera, 1.5);
        const back = m.warpTransform({x_m: -0.5, y_m: 0, theta_rad: 0}, camera, 1.5);
        // The vanishing point is a fixed point of the transform.
        const vpAfter = [fwd.scale * camera.vpX + fwd.tx, fwd.scale * camera.vpY + fwd.ty];
        return {fwd: fwd.scale, back: back.scale, vp: [camera.vpX, camera.vpY], vpAfter, shift: fwd.shiftX};
    """)
    assert result["fwd"] == pytest.approx(1.5 / 1.0)
    assert result["back"] == pytest.approx(1.5 / 2.0)
    assert result["vpAfter"] == pytest.approx(result["vp"])
    # The camera looks 12 degrees down: the horizon (vanishing point) is above the image centre.
    assert result["vp"][1] < 120
    assert result["shift"] == pytest.approx(0.0, abs=1e-9)


def test_turning_while_driving_combines_shift_and_scale(module_page) -> None:
    result = run(module_page, f"""
        const camera = m.cameraModel({{}});
        const pose = m.integrateCommands({held(1.0, 0.3, 0.4)}, 1000);
        const t = m.warpTransform(pose, camera);
        return {{pose, shift: t.shiftX, scale: t.scale}};
    """)
    assert result["pose"]["x_m"] > 0.1 and result["pose"]["y_m"] > 0 and result["pose"]["theta_rad"] > 0.2
    assert result["shift"] > 0 and result["scale"] > 1.0


def test_acceleration_limits_and_the_deadman_hold_shape_the_prediction(module_page) -> None:
    result = run(module_page, """
        const one = [{sequence: 1, sentMs: 0, linear_mps: 0.5, angular_radps: 0}];
        const ramped = m.integrateCommands(one, 400);
        const stalled = m.integrateCommands(one, 5000);
        return {ramped: ramped.x_m, speed: ramped.linear_mps, stalled: stalled.x_m, end: stalled.linear_mps};
    """)
    # 1 m/s^2 from rest: 0.4 s reach 0.4 m/s and cover 0.08 m, not 0.5 * 0.4 = 0.2 m.
    assert result["speed"] == pytest.approx(0.4, abs=1e-6)
    assert result["ramped"] == pytest.approx(0.08, abs=0.005)
    # One command alone holds for the deadman's 0.4 s, then the robot brakes to a stop.
    assert result["end"] == 0 and result["stalled"] == pytest.approx(0.16, abs=0.01)


def test_only_commands_after_the_frames_last_applied_sequence_warp_and_new_frames_fall_back(module_page) -> None:
    result = run(module_page, """
        const log = new m.CommandLog();
        log.reset(1000);                               // the drive socket's sequence_base
        for (let i = 1; i <= 20; i += 1) {
          log.recordSent({type: "drive", sequence: i, linear_mps: 0, angular_radps: 1}, i * 50);
        }
        const before = log.outstanding().map((c) => c.sequence);
        const full = log.predict(1050).theta_rad;
        log.recordFrame({last_applied_sequence: 1010}, 1600); // the frame shows our commands 1..10
        const after = log.outstanding().map((c) => c.sequence);
        const rest = log.predict(1050).theta_rad;
        const delay = log.measuredDelayMs;
        log.recordFrame({last_applied_sequence: 1005}, 1700); // an older frame changes nothing
        const still = log.outstanding().length;
        log.recordSent({type: 'stop', sequence: 21}, 1100);
        log.recordFrame({last_applied_sequence: 1021}, 2100);
        const none = log.outstanding().length;
        const other = new m.CommandLog();
        other.reset(50);
        other.recordSent({type: 'drive', sequence: 1, linear_mps: 0.2, angular_radps: 0}, 0);
        other.recordFrame({last_applied_sequence: 7}, 10);   // another driver's older command: ours still due
        return {before, after, full, rest, delay, still, none, otherOutstanding: other.outstanding().length,
                kept: log.commands.length};
    """)
    assert result["before"] == list(range(1, 21))
    assert result["after"] == list(range(11, 21))
    assert result["rest"] < result["full"]
    # Command 10 was sent at 500 ms and first shown by the frame that arrived at 1600 ms.
    assert result["delay"] == pytest.approx(1100)
    assert result["still"] == 10
    assert result["none"] == 0 and result["kept"] == 1  # the shown stop stays: it is the velocity at capture
    assert result["otherOutstanding"] == 1


def test_the_predicted_path_lies_on_the_floor_below_the_horizon_and_bends_with_the_turn(module_page) -> None:
    result = run(module_page, """
        const camera = m.cameraModel({});
        const straight = m.predictedPathPoints(camera, {linear_mps: 0.3, angular_radps: 0});
        const left = m.predictedPathPoints(camera, {linear_mps: 0.3, angular_radps: 0.8});
        const still = m.predictedPathPoints(camera, {linear_mps: 0, angular_radps: 1});
        return {straight, left, still: still.length, vpY: camera.vpY};
    """)
    assert len(result["straight"]) > 5 and result["still"] == 0
    assert all(abs(p["x"] - 160) < 1e-6 and p["y"] > result["vpY"] for p in result["straight"])
    ys = [p["y"] for p in result["straight"]]
    assert ys == sorted(ys, reverse=True)  # further along the path is higher in the picture
    assert result["left"][-1]["x"] < 160


@pytest.mark.parametrize("hostile", ["NaN", "undefined", "'x'", "-5", "1e9"])
def test_hostile_camera_numbers_fall_back_to_a_sane_model(module_page, hostile: str) -> None:
    result = run(module_page, f"""
        const c = m.cameraModel({{width: {hostile}, height: {hostile}, hfovDeg: {hostile}}});
        const t = m.warpTransform({{x_m: {hostile}, y_m: 0, theta_rad: {hostile}}}, c);
        return [c.f, c.width, t.scale, t.tx, t.ty].every(Number.isFinite);
    """)
    assert result is True


def scan_js(ranges: str) -> str:
    """A 181-beam laser scan over -90..90 degrees (the Telebot's) with the given JS ranges array."""
    return f"{{angle_min_rad: -Math.PI / 2, angle_increment_rad: Math.PI / 180, ranges_m: {ranges}}}"


def test_the_zoom_depth_is_the_median_laser_range_inside_the_cameras_field_of_view(module_page) -> None:
    result = run(module_page, f"""
        const camera = m.cameraModel({{width: 320, height: 240, hfovDeg: 60}});
        // 3 m straight ahead within +-30 degrees, a 0.4 m wall beside the robot outside the view.
        const ranges = Array.from({{length: 181}}, (_, i) => Math.abs(i - 90) <= 30 ? 3 : 0.4);
        const inView = m.referenceDepthFromScan({scan_js("ranges")}, camera);
        const far = m.referenceDepthFromScan({scan_js("ranges.map(() => 50)")}, camera);
        const near = m.referenceDepthFromScan({scan_js("ranges.map(() => 0.01)")}, camera);
        const noEcho = m.referenceDepthFromScan({scan_js("ranges.map(() => null)")}, camera);
        const hostile = [null, {{}}, {{angle_min_rad: 'x', angle_increment_rad: 0.1, ranges_m: [1, 2, 3, 4, 5, 6]}},
                         {{angle_min_rad: 0, angle_increment_rad: -1, ranges_m: [1, 1, 1, 1, 1, 1]}}]
          .map((scan) => m.referenceDepthFromScan(scan, camera));
        const pose = {{x_m: -0.5, y_m: 0, theta_rad: 0}};
        return {{inView, far, near, noEcho: String(noEcho), hostile: hostile.map(String),
                 scaleAt3: m.warpTransform(pose, camera, inView).scale,
                 scaleDefault: m.warpTransform(pose, camera).scale}};
    """)
    assert result["inView"] == pytest.approx(3.0)
    assert result["far"] == pytest.approx(8.0) and result["near"] == pytest.approx(0.3)  # clamped to the lab's sizes
    assert result["hostile"] == ["NaN"] * 4 and result["noEcho"] == "NaN"
    # Backing away 0.5 m from surfaces 3 m off shrinks the picture to 3/3.5, not to 1.5/2.
    assert result["scaleAt3"] == pytest.approx(3 / 3.5)
    assert result["scaleDefault"] == pytest.approx(1.5 / 2.0)


def test_edge_fill_covers_exactly_what_the_warped_picture_leaves_uncovered(module_page) -> None:
    result = run(module_page, """
        const camera = m.cameraModel({width: 320, height: 240});
        const area = (rects) => rects.reduce((sum, r) => sum + r[6] * r[7], 0);
        const turned = {scale: 1, tx: 100, ty: 0, shiftX: 100};
        const shrunk = m.warpTransform({x_m: -0.5, y_m: 0, theta_rad: 0}, camera, 1.5);
        const gone = {scale: 1, tx: 1280, ty: 0, shiftX: 1280};
        const size = {width: 320, height: 240};
        return {
          turned: m.edgeFillRects(turned, size, size),
          shrunkArea: area(m.edgeFillRects(shrunk, size, size)),
          shrunkPicture: (shrunk.scale * 320) * (shrunk.scale * 240),
          gone: m.edgeFillRects(gone, size, size),
          still: m.edgeFillRects({scale: 1, tx: 0, ty: 0, shiftX: 0}, size, size).length,
          warped: [m.isWarped(turned), m.isWarped({scale: 1, tx: 0, ty: 0, shiftX: 0.01})],
        };
    """)
    # A left turn moves the picture 100 px right: the left 100 columns continue the picture's first column.
    assert result["turned"] == [[0, 0, 1, 240, 0, 0, 100, 240]]
    # Backing away leaves a border all round: the eight zones and the picture tile the canvas.
    assert result["shrunkArea"] + result["shrunkPicture"] == pytest.approx(320 * 240)
    # Turned right out of sight: the whole canvas continues the first column.
    assert result["gone"] == [[0, 0, 1, 240, 0, 0, 320, 240]]
    assert result["still"] == 0 and result["warped"] == [True, False]


def test_the_panel_fills_the_uncovered_view_with_continued_edges_or_black(module_page) -> None:
    result = module_page.evaluate("""async () => {
        const { drawWarped } = await import('/panels/camera-panel/camera-feedback.js');
        const source = new OffscreenCanvas(320, 240);
        const sctx = source.getContext('2d');
        sctx.fillStyle = 'rgb(200, 40, 40)';
        sctx.fillRect(0, 0, 320, 240);
        const bitmap = await createImageBitmap(source);
        const canvas = document.createElement('canvas');
        canvas.width = 320; canvas.height = 240;
        const ctx = canvas.getContext('2d');
        const turned = {scale: 1, tx: 100, ty: 0, shiftX: 100};
        const pixel = () => Array.from(ctx.getImageData(40, 120, 1, 1).data.slice(0, 3));
        drawWarped(ctx, bitmap, turned, 'edges');
        const edges = pixel();
        drawWarped(ctx, bitmap, turned, 'black');
        const black = pixel();
        return {edges, black};
    }""")
    assert result["edges"] == [200, 40, 40]
    assert result["black"] == [0, 0, 0]
