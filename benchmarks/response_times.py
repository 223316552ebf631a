"""The 2003 paper's table 1 on this lab: response times of real skill activations and drive commands, per leg.

Run `python -m benchmarks.response_times [--quick] [--output DIR]`: a student's console in headless Chromium
activates a skill several times and drives by the keyboard; the table is computed here from the commands the
console's response-times panel timed, beside what the panel shows for the same run (they must agree to its one
decimal), and beside the middleware's own robot leg as it answered each activation. Writes DIR/response_times.json.
Anchors: 138 ms total on the paper's LAN (131.89 min, 148.65 max), 10.89 ms middleware to skill server.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path
from typing import Any

from benchmarks.report import Measurement, print_table, write_json

KINDS = ("skill", "drive")
LEGS = ("total", "client", "robot")
FIGURES = ("min", "mean", "max", "jitter")
SHOWN_DECIMALS = 1
KIND_NAMES = {"skill": "skill activations", "drive": "drive commands"}


def leg_figures(values: list[float]) -> dict[str, float]:
    """count, min, max, mean, q1, q3 and jitter (q3 - q1) of round trips [ms]: the panel's figures
    (lib/stats.js legFigures), quartiles interpolated linearly between ranks."""
    numbers = sorted(v for v in values if isinstance(v, int | float) and v == v and abs(v) != float("inf"))
    if not numbers:
        nan = float("nan")
        return {"count": 0, "min": nan, "max": nan, "mean": nan, "q1": nan, "q3": nan, "jitter": nan}
    q1, _, q3 = statistics.quantiles(numbers, n=4, method="inclusive") if len(numbers) > 1 else numbers * 3
    return {"count": len(numbers), "min": numbers[0], "max": numbers[-1], "mean": statistics.fmean(numbers),
            "q1": q1, "q3": q3, "jitter": q3 - q1}


def table_one(samples: dict[str, list[dict[str, float]]]) -> dict[str, dict[str, dict[str, float]]]:
    """{kind: {leg: figures}} of the timed commands ({kind: [{total_ms, client_ms, robot_ms}, ...]})."""
    return {kind: {leg: leg_figures([sample[f"{leg}_ms"] for sample in samples.get(kind, [])
                                     if sample.get(f"{leg}_ms") is not None]) for leg in LEGS} for kind in KINDS}


def shown_table(page: Any) -> dict[str, dict[str, dict[str, float]]]:
    """What the console's response-times panel shows, read from its cells as numbers (NaN for "—")."""
    def number(field: str) -> float:
        text = (page.locator(f'response-times-panel [data-field="{field}"]').text_content() or "").strip()
        try:
            return float(text)
        except ValueError:
            return float("nan")

    return {kind: {leg: {figure: number(f"rtt-{kind}-{leg}-{figure}") for figure in FIGURES} | {
        "count": number(f"rtt-{kind}-count")} for leg in LEGS} for kind in KINDS}


def disagreements(shown: dict, computed: dict) -> list[str]:
    """Each figure the panel shows that is not the computed one to its decimals."""
    tolerance = 0.5 * 10 ** -SHOWN_DECIMALS + 1e-9
    wrong = []
    for kind in KINDS:
        for leg in LEGS:
            for figure in FIGURES:
                a, b = shown[kind][leg][figure], computed[kind][leg][figure]
                if (a != a) != (b != b) or (a == a and abs(a - b) > tolerance):
                    wrong.append(f"{kind} {leg} {figure}: panel {a}, computed {b:.3f}")
    return wrong


def panel_samples(page: Any) -> dict[str, list[dict[str, float]]]:
    """The commands the panel timed (NaN legs as None)."""
    return page.evaluate("""() => {
      const { skill, drive } = document.querySelector('response-times-panel').samples;
      const plain = (s) => ({ total_ms: s.total_ms, client_ms: Number.isFinite(s.client_ms) ? s.client_ms : null,
        robot_ms: Number.isFinite(s.robot_ms) ? s.robot_ms : null });
      return { skill: skill.map(plain), drive: drive.map(plain) };
    }""")


def show_panel(page: Any, panel_id: str) -> None:
    """Opens the console tab holding the panel."""
    tab = page.locator(f'section[data-panel-id="{panel_id}"]').get_attribute("data-tab")
    page.locator(f'[role="tab"][data-tab="{tab}"]').click()


def activate_and_drive(page: Any, activations: int, drive_s: float) -> list[float]:
    """Activates orientation control activations times (to the heading the robot has, so each ends at once) and
    drives forward by the keyboard for drive_s; the robot legs the middleware answered the activations with."""
    robot_legs: list[float] = []

    def note(response: Any) -> None:
        if response.request.method == "POST" and "/skills/orientation_control/goals" in response.url:
            robot_legs.append(response.json()["robot_rtt_ms"])

    page.on("response", note)
    show_panel(page, "skill-orientation_control")
    panel = page.locator('skill-panel[data-skill="orientation_control"]')
    for done in range(1, activations + 1):
        heading = (page.locator('odometry-panel [data-field="heading-rad"]').text_content() or "0").strip()
        panel.locator('input[name="heading_rad"]').fill(heading)
        panel.locator('button[data-action="activate"]').click()
        # The panel still says "succeeded" from the last one: wait for this activation's timing, then its end.
        page.wait_for_function(f"() => document.querySelector('response-times-panel').samples.skill.length >= {done}",
                               timeout=60_000)
        page.locator('skill-panel[data-skill="orientation_control"][data-status="succeeded"]').wait_for(
            timeout=60_000)
    page.evaluate("document.activeElement && document.activeElement.blur()")
    page.keyboard.down("ArrowDown")
    page.wait_for_timeout(drive_s * 1000)
    page.keyboard.up("ArrowDown")
    page.wait_for_timeout(500)  # the last acks and the stop's
    page.remove_listener("response", note)
    return robot_legs


def measure(activations: int, drive_s: float) -> dict[str, Any]:
    """One student's console on a lab started for it: the panel's samples, its table and the middleware's legs."""
    from benchmarks.browser_view import chromium, chromium_page, open_console
    from benchmarks.lab_under_test import PASSWORD, LabUnderTest

    lab = LabUnderTest(users=1)
    try:
        with chromium() as browser, chromium_page(browser) as (page, errors):
            open_console(page, lab.middleware.url, lab.usernames[0], PASSWORD)
            page.locator('queue-panel[data-role="controller"]').wait_for(timeout=30_000)
            page.locator('odometry-panel [data-field="heading-rad"]').filter(has_text=".").wait_for()
            robot_legs = activate_and_drive(page, activations, drive_s)
            show_panel(page, "response-times")
            page.wait_for_timeout(1200)  # two of the panel's refreshes
            samples = panel_samples(page)
            shown = shown_table(page)
            delivery = {name: page.locator(f'response-times-panel [data-field="rtt-{name}"]').text_content()
                        for name in ("throughput", "sent", "late", "lost")}
            if errors:
                raise RuntimeError(f"JavaScript errors in the console: {errors}")
    finally:
        lab.stop()
    return {"samples": samples, "shown": shown, "robot_legs_answered_ms": robot_legs, "delivery": delivery}


def rows_of(table: dict, wrong: list[str]) -> list[Measurement]:
    """Table 1's rows: min, mean, max and jitter of each leg of each kind of command."""
    rows = []
    for kind in KINDS:
        for leg in LEGS:
            figures = table[kind][leg]
            for figure in FIGURES:
                rows.append(Measurement(KIND_NAMES[kind], f"{leg}, {figure}", figures[figure], "ms", "-",
                                        note=f"{figures['count']} timed"))
    rows.append(Measurement("panel vs table", "figures that disagree", float(len(wrong)), "count", "0",
                            passed=not wrong, note="; ".join(wrong)[:200]))
    return rows


def run(quick: bool, output: Path) -> list[Measurement]:
    activations, drive_s = (3, 1.0) if quick else (20, 10.0)
    measured = measure(activations, drive_s)
    table = table_one(measured["samples"])
    wrong = disagreements(measured["shown"], table)
    rows = rows_of(table, wrong)
    print_table("Response times per leg (the 2003 paper's table 1), beside the console's panel for the same run",
                rows)
    output.mkdir(parents=True, exist_ok=True)
    write_json(output / "response_times.json", rows, {
        "quick": quick, "activations": activations, "drive_s": drive_s, "table_one_ms": table,
        "panel_shows": measured["shown"], "panel_agrees": not wrong, "delivery": measured["delivery"],
        "robot_legs_answered_ms": measured["robot_legs_answered_ms"], "samples": measured["samples"],
        "load_average": os.getloadavg()[0], "cpu_count": os.cpu_count()})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--output", default="bench-results")
    args = parser.parse_args(argv)
    rows = run(args.quick, Path(args.output))
    return 0 if all(row.passed is not False for row in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
