"""The response-time figures' pure maths (client_ui/static/lib/stats.js, lib/response-times.js) and the odometry
panel's "last command applied" line, run in headless Chromium against values computed by hand."""

from __future__ import annotations

import random

import pytest

from benchmarks.response_times import leg_figures

pytestmark = pytest.mark.e2e


def run(page, body: str):
    """Evaluates body in the page, with `stats`, `rt` and `odometry` imported."""
    return page.evaluate(f"""async () => {{
        const stats = await import('/lib/stats.js');
        const rt = await import('/lib/response-times.js');
        const odometry = await import('/panels/odometry-panel/odometry-panel.js');
        {body} }}""")


def test_min_max_mean_and_jitter_are_the_hand_computed_ones(module_page) -> None:
    result = run(module_page, """return {
        four: stats.legFigures([40, 10, 30, 20]),
        seven: stats.legFigures([7, 1, 6, 2, 5, 3, 4]),
        one: stats.legFigures([5]),
        dirty: stats.legFigures([1, NaN, 'x', Infinity, 3]),
        none: Object.values(stats.legFigures([])).slice(1).every(Number.isNaN),
    };""")
    # Sorted 10 20 30 40: Q1 at rank 0.75 -> 17.5, Q3 at rank 2.25 -> 32.5 (linear between ranks).
    assert result["four"] == {"count": 4, "min": 10, "max": 40, "mean": 25, "q1": 17.5, "q3": 32.5, "jitter": 15}
    # 1..7: Q1 at rank 1.5 -> 2.5, Q3 at rank 4.5 -> 5.5.
    assert result["seven"] == {"count": 7, "min": 1, "max": 7, "mean": 4, "q1": 2.5, "q3": 5.5, "jitter": 3}
    assert result["one"] == {"count": 1, "min": 5, "max": 5, "mean": 5, "q1": 5, "q3": 5, "jitter": 0}
    assert result["dirty"] == {"count": 2, "min": 1, "max": 3, "mean": 2, "q1": 1.5, "q3": 2.5, "jitter": 1}
    assert result["none"] is True


def test_the_benchmarks_python_figures_are_the_panels(module_page) -> None:
    series = [[round(random.Random(seed).lognormvariate(2, 0.6), 3) for _ in range(seed * 7 + 1)]
              for seed in range(1, 6)]
    figures = run(module_page, f"return {series}.map((values) => stats.legFigures(values));")
    for values, browser in zip(series, figures, strict=True):
        python = leg_figures(values)
        for name in ("count", "min", "max", "mean", "q1", "q3", "jitter"):
            assert browser[name] == pytest.approx(python[name], abs=1e-9), (name, values)


def test_a_command_is_split_into_its_two_legs_and_late_and_lost_ones_are_counted(module_page) -> None:
    result = run(module_page, """
        const log = new rt.TimingLog();
        log.sent('drive', 1, 0, 60); log.answered('drive', 1, 12, {robotMs: 2, bytes: 90});
        log.sent('drive', 2, 100, 60); log.answered('drive', 2, 1300, {robotMs: 4, bytes: 90});
        log.sent('drive', 3, 200, 60);                       // never answered: lost after 5 s
        log.sent('drive', 4, 300, 60); log.answeredOldest('drive', 350, {bytes: 80});  // a refusal answers #3
        log.sent('skill', 1, 1000, 40); log.answered('skill', 1, 1030, {robotMs: 50, bytes: 400});
        const repeat = log.answered('drive', 1, 20, {robotMs: 1});
        const before = log.delivery();
        log.expire(5299);
        const atFive = log.delivery();
        log.expire(5300);
        return {drive: log.samples('drive'), skill: log.samples('skill'), figures: log.figures('drive'),
                before, atFive, after: log.delivery(), repeat,
                throughput: log.throughput(1300, 10000), later: log.throughput(11400, 10000)};
    """)
    assert [(s["total_ms"], s["client_ms"], s["robot_ms"]) for s in result["drive"]] == [(12, 10, 2), (1200, 1196, 4)]
    # A robot leg longer than the whole round trip (clocks apart) is capped at it: the browser leg is never negative.
    assert [(s["total_ms"], s["client_ms"], s["robot_ms"]) for s in result["skill"]] == [(30, 0, 30)]
    assert result["figures"]["total"]["min"] == 12 and result["figures"]["total"]["max"] == 1200
    assert result["figures"]["robot"]["mean"] == 3
    assert result["repeat"] is None
    assert result["before"] == {"sent": 5, "answered": 4, "late": 1, "lost": 0, "waiting": 1}
    assert result["atFive"]["lost"] == 0
    assert result["after"] == {"sent": 5, "answered": 4, "late": 1, "lost": 1, "waiting": 0}
    # Within 10 s of t=1300: 4 * 60 + 40 sent, 90 + 90 + 80 + 400 answered -> 940 bytes over 10 s.
    assert result["throughput"] == pytest.approx(94.0)
    assert result["later"] == pytest.approx(0.0)


def test_a_new_drive_connection_counts_what_the_old_one_left_unanswered_as_lost(module_page) -> None:
    result = run(module_page, """
        const log = new rt.TimingLog();
        log.sent('drive', 1, 0); log.sent('drive', 2, 50); log.sent('skill', 1, 60);
        log.expire(100, 'drive');
        log.sent('drive', 1, 120); log.answered('drive', 1, 130, {robotMs: 1});
        return log.delivery();
    """)
    assert result == {"sent": 4, "answered": 1, "late": 0, "lost": 2, "waiting": 1}


def test_commands_the_server_superseded_by_a_newer_one_are_answered_untimed_not_lost(module_page) -> None:
    result = run(module_page, """
        const log = new rt.TimingLog();
        for (let sequence = 1; sequence <= 4; sequence += 1) log.sent('drive', sequence, sequence * 50);
        log.sent('skill', 1, 60);
        log.supersededBefore('drive', 4, 400);   // the ack of #4 said 3 waiting commands were superseded
        log.answered('drive', 4, 400, {robotMs: 2});
        log.sent('drive', 5, 450);
        log.expire(6000);
        return {delivery: log.delivery(), timed: log.samples('drive').length};
    """)
    # #1-#3 answered by being superseded (untimed), #4 timed; #5 and the skill, never answered, lost.
    assert result == {"delivery": {"sent": 6, "answered": 4, "late": 0, "lost": 2, "waiting": 0}, "timed": 1}


def test_the_odometry_panel_says_how_long_ago_a_command_was_applied_not_its_sequence_number(module_page) -> None:
    result = run(module_page, """return [NaN, 0, 999, 42500, 125000, 7300000].map((ago) =>
        odometry.appliedAgo(Number.isNaN(ago) ? NaN : 1000000 - ago, 1000000));""")
    assert result == ["none since this panel opened", "just now", "just now", "42 s ago", "2 min ago", "2 h ago"]


def test_the_report_a_tutor_reads_carries_the_panel_s_figures_and_none_as_null(module_page) -> None:
    result = run(module_page, """
        const log = new rt.TimingLog();
        log.sent('skill', 1, 0, 100); log.answered('skill', 1, 40, {robotMs: 10, bytes: 300});
        log.sent('skill', 2, 100, 100); log.answered('skill', 2, 180, {robotMs: 30, bytes: 300});
        const report = rt.reportOf(log, 1000, 10000);
        return {report, line: rt.reportLine(report, 'skill'), none: rt.reportLine(report, 'drive'),
                nothing: rt.reportLine(null, 'skill')};
    """)
    report = result["report"]
    # Totals 40 and 80 ms: Q1 = 50, Q3 = 70; robot legs 10 and 30; browser legs 30 and 50.
    assert report["skill"] == {"count": 2, "total": {"min": 40, "mean": 60, "max": 80, "jitter": 20},
                               "client": {"min": 30, "mean": 40, "max": 50, "jitter": 10},
                               "robot": {"min": 10, "mean": 20, "max": 30, "jitter": 10}}
    assert report["drive"]["count"] == 0 and report["drive"]["total"] == dict.fromkeys(
        ["min", "mean", "max", "jitter"])
    assert report["delivery"] == {"sent": 2, "late": 0, "lost": 0}
    assert report["throughput_bps"] == pytest.approx(80.0)  # 800 bytes over 10 s
    assert result["line"] == "2 skill activations: 40.0–80.0 ms, mean 60.0, jitter 20.0"
    assert result["none"] == "no drive commands" and result["nothing"] == "no skill activations"
