"""The per-part comparison of a lesson's tests before and after: shares of marked points per topic, ratings apart."""

from __future__ import annotations

from middleware.teaching.lesson_tests import WHOLE_TEST, compare_parts, part_totals, with_overrides


def _result(item: str, points: float, max_points: float, *topics: str) -> dict:
    return {"item": item, "points": points, "max_points": max_points, "topics": list(topics)}


def test_each_part_compares_its_share_of_points_and_ratings_stay_out_of_the_marks() -> None:
    before = part_totals([([_result("1", 0, 1, "part 1"), _result("2", 1, 2, "part 2")], {})])
    after = part_totals([([_result("1", 1, 1, "part 1"), _result("2", 2, 2, "part 2"),
                           _result("9", 0, 0, "part 1"), _result("10", 0, 0, "part 2")], {"9": 4, "10": 2}),
                         ([_result("1", 1, 1, "part 1"), _result("2", 0, 2, "part 2"),
                           _result("9", 0, 0, "part 1")], {"9": 5})])
    rows = {row.part: row for row in compare_parts(before, after)}
    assert list(rows) == ["part 1", "part 2", WHOLE_TEST]
    assert (rows["part 1"].before, rows["part 1"].after, rows["part 1"].change) == (0.0, 1.0, 1.0)
    assert (rows["part 2"].before, rows["part 2"].after, rows["part 2"].change) == (0.5, 0.5, 0.0)
    assert (rows["part 1"].rating_after, rows["part 2"].rating_after, rows["part 1"].rating_before) == (4.5, 2.0, None)
    assert (rows[WHOLE_TEST].before, rows[WHOLE_TEST].after) == (round(1 / 3, 4), round(4 / 6, 4))


def test_a_part_only_rated_has_no_share_and_a_tutors_mark_counts() -> None:
    rows = compare_parts(part_totals([]), part_totals([([_result("9", 0, 0, "part 3")], {"9": 3})]))
    assert [(r.part, r.before, r.after, r.change, r.rating_after) for r in rows] == [("part 3", None, None, None, 3.0)]

    class Review:
        def __init__(self, id_: int, item: str, points: float) -> None:
            self.id, self.item, self.points = id_, item, points

    fixed = with_overrides([_result("1", 0, 2, "part 1")], [Review(2, "1", 2.0), Review(1, "1", 1.0)])
    assert fixed[0]["points"] == 2.0
