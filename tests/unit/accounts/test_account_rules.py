"""Account, course, CSV, invitation and login-limit rules on SQLite and PostgreSQL, with a controllable clock."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest
from sqlalchemy import func, select
from sqlalchemy.orm import Session, sessionmaker

from middleware.accounts import invitations, services
from middleware.auth import throttle
from middleware.auth.schemas import InvalidField
from middleware.auth.services import change_own_password, create_user, log_in
from middleware.courses import services as courses
from middleware.courses.schemas import CourseSettings, csv_safe, parse_settings, report_csv
from middleware.errors import Refused
from middleware.models import CourseMembership, Invitation, LoginFailure, User
from tests.unit.bookings.conftest import People

NOW = datetime(2026, 11, 23, 9, 0, tzinfo=UTC)
PASSWORD = "correct-horse-battery"


def _user(session: Session, user_id: int) -> User:
    user = session.get(User, user_id)
    assert user is not None
    return user


def _memberships(session: Session, course_id: int) -> int:
    return session.scalar(select(func.count()).select_from(CourseMembership)
                          .where(CourseMembership.course_id == course_id)) or 0


# --- CSV enrolment ----------------------------------------------------------------------------


def test_csv_enrols_existing_students_creates_new_ones_and_reports_every_refused_row(factory, people: People) -> None:
    with factory() as session:
        create_user(session, "loner", "student", PASSWORD)
        create_user(session, "gone", "student", PASSWORD)
        session.scalar(select(User).where(User.username == "gone")).is_active = False
        session.commit()
        data = ("\ufeffUsername,email\n"
                "loner,l@example.org\n"      # existing student: enrolled
                "newkid,\n"                  # unknown: created with a generated password
                ",\n"                        # empty row
                "Bad Name!,\n"               # not a valid username
                "LONER,\n"                   # duplicate of line 2 (usernames are case-insensitive)
                "stud,\n"                    # already enrolled
                "tut,\n"                     # a tutor's account
                "gone,\n"                    # disabled account
                "=HYPERLINK(1),\n").encode()  # a formula: refused as a username
        report = courses.enrol_from_csv(session, _user(session, people.tutor), people.course, data)
        session.commit()
        assert report.enrolled == ["loner"]
        assert [name for name, _ in report.created] == ["newkid"]
        reasons = {line: reason for line, _value, reason in report.refused}
        assert sorted(reasons) == [4, 5, 6, 7, 8, 9, 10]
        assert "no username" in reasons[4]
        assert "username must be" in reasons[5]
        assert "line 2" in reasons[6]
        assert "already enrolled" in reasons[7]
        assert "tutor account" in reasons[8]
        assert "disabled" in reasons[9]
        created = session.scalar(select(User).where(User.username == "newkid"))
        assert created is not None and created.role == "student"
        assert log_in(session, "newkid", report.created[0][1], "10.0.0.1", NOW).user is not None
        exported = report_csv(report.enrolled, report.created, report.refused)
        assert "'=HYPERLINK(1)" in exported and "\n=" not in exported


@pytest.mark.parametrize(("data", "message"), [
    (b"\xff\xfeu\x00s\x00", "not UTF-8"),
    (b"name\nalice\n", "'username' column"),
    (b"", "empty"),
    (b"username\n" + b"x\n" * 501, "at most 500"),
])
def test_unreadable_csv_files_are_refused_whole_and_change_nothing(factory, people: People, data: bytes,
                                                                   message: str) -> None:
    with factory() as session:
        before = _memberships(session, people.course)
        with pytest.raises(InvalidField, match=message) as caught:
            courses.enrol_from_csv(session, _user(session, people.tutor), people.course, data)
        assert caught.value.field == "file"
        session.rollback()
        assert _memberships(session, people.course) == before


def test_csv_cells_that_look_like_formulas_are_quoted() -> None:
    assert [csv_safe(v) for v in ("=1+1", "+1", "-1", "@SUM", "ok")] == ["'=1+1", "'+1", "'-1", "'@SUM", "ok"]


def test_only_the_courses_tutors_and_admins_manage_a_course(factory, people: People) -> None:
    with factory() as session:
        for actor in (people.other_tutor, people.student):
            with pytest.raises(Refused) as refused:
                courses.enrol_from_csv(session, _user(session, actor), people.course, b"username\nzed\n")
            assert refused.value.status == 403
            with pytest.raises(Refused):
                courses.update_settings(session, _user(session, actor), people.course, CourseSettings(turn_length_s=60))
        courses.update_settings(session, _user(session, people.admin), people.course, CourseSettings(turn_length_s=60))
        with pytest.raises(Refused) as missing:
            courses.managed_course(session, _user(session, people.admin), 999_999)
        assert missing.value.status == 404


def test_a_tutor_who_creates_a_course_becomes_its_tutor_and_students_cannot_create(factory, people: People) -> None:
    with factory() as session:
        course = courses.create_course(session, _user(session, people.other_tutor), "nav-2", "Navigation",
                                       parse_settings({"turn_length_s": "300", "booking_allowance_min": "0"}))
        assert course.code == "NAV-2" and course.booking_allowance_min == 0
        assert courses.is_course_tutor(session, people.other_tutor, course.id)
        with pytest.raises(Refused):
            courses.create_course(session, _user(session, people.student), "X1", "X", CourseSettings())
        with pytest.raises(Refused) as taken:
            courses.create_course(session, _user(session, people.tutor), "nav-2", "Again", CourseSettings())
        assert taken.value.field == "code"


@pytest.mark.parametrize(("field", "value"), [
    ("turn_length_s", "9"), ("turn_length_s", "3601"), ("turn_length_s", "1e3"), ("turn_length_s", True),
    ("booking_allowance_min", "-1"), ("booking_allowance_min", 10081), ("title", "  "), ("title", "a\nb"),
])
def test_course_settings_out_of_range_name_the_field(field: str, value: object) -> None:
    with pytest.raises(InvalidField) as caught:
        parse_settings({field: value})
    assert caught.value.field == field


# --- invitations ---------------------------------------------------------------------------------


def test_an_invitation_makes_one_account_enrolled_in_its_course_and_works_once(factory, people: People) -> None:
    with factory() as session:
        invitation, token = invitations.create_invitation(session, _user(session, people.tutor), "student",
                                                          people.course, timedelta(days=7), NOW)
        session.commit()
        assert token not in invitation.token_hash and len(invitation.token_hash) == 64
        user = invitations.accept(session, token, "newbie", PASSWORD, PASSWORD, NOW + timedelta(days=1))
        session.commit()
        assert user.role == "student" and courses.members(session, _user(session, people.tutor), people.course)
        assert session.scalar(select(CourseMembership.role).where(CourseMembership.user_id == user.id)) == "student"
        with pytest.raises(invitations.InvitationUnusable) as used:
            invitations.accept(session, token, "second", PASSWORD, PASSWORD, NOW + timedelta(days=1))
        assert used.value.reason == "used"


def test_expired_and_unknown_invitations_are_refused(factory, people: People) -> None:
    with factory() as session:
        _, token = invitations.create_invitation(session, _user(session, people.admin), "tutor", None,
                                                 timedelta(days=1), NOW)
        session.commit()
        with pytest.raises(invitations.InvitationUnusable) as expired:
            invitations.find_usable(session, token, NOW + timedelta(days=1, seconds=1))
        assert expired.value.reason == "expired"
        with pytest.raises(invitations.InvitationUnusable) as unknown:
            invitations.find_usable(session, token[:-2] + "xx", NOW)
        assert unknown.value.reason == "unknown"
        assert session.scalar(select(func.count()).select_from(User).where(User.username == "x")) == 0


@pytest.mark.parametrize(("actor", "role", "course"), [
    ("tutor", "tutor", "course"), ("tutor", "admin", "course"), ("tutor", "student", "other_course"),
    ("tutor", "student", None), ("student", "student", "course"), ("other_tutor", "student", "course"),
])
def test_invitations_of_the_wrong_role_or_course_are_refused(factory, people: People, actor: str, role: str,
                                                             course: str | None) -> None:
    with factory() as session:
        with pytest.raises(Refused) as refused:
            invitations.create_invitation(session, _user(session, getattr(people, actor)), role,
                                          getattr(people, course) if course else None, timedelta(days=7), NOW)
        assert refused.value.status == 403
        session.rollback()
        assert session.scalar(select(func.count()).select_from(Invitation)) == 0


# --- passwords -----------------------------------------------------------------------------------


def test_password_change_needs_the_current_password(factory, people: People) -> None:
    with factory() as session:
        user = create_user(session, "ada", "student", PASSWORD)
        with pytest.raises(InvalidField) as wrong:
            change_own_password(session, user, "not-my-password", "a-brand-new-secret")
        assert wrong.value.field == "current_password"
        with pytest.raises(InvalidField):
            change_own_password(session, user, PASSWORD, "short")
        change_own_password(session, user, PASSWORD, "a-brand-new-secret")
        session.commit()
        assert log_in(session, "ada", "a-brand-new-secret", "10.0.0.1", NOW).user is not None


@pytest.mark.parametrize(("actor", "target", "allowed"), [
    ("tutor", "student", True), ("admin", "student", True), ("admin", "tutor", True),
    ("other_tutor", "student", False), ("student", "other_student", False), ("tutor", "other_tutor", False),
    ("tutor", "admin", False),
])
def test_password_reset_permissions(factory, people: People, actor: str, target: str, allowed: bool) -> None:
    with factory() as session:
        target_user = _user(session, getattr(people, target))
        before = target_user.password_hash
        if allowed:
            _, password = services.reset_password(session, _user(session, getattr(people, actor)), target_user.id)
            assert len(password) >= 10 and target_user.password_hash != before
        else:
            with pytest.raises(Refused) as refused:
                services.reset_password(session, _user(session, getattr(people, actor)), target_user.id)
            assert refused.value.status == 403
            assert target_user.password_hash == before


def test_an_admin_cannot_disable_or_demote_themself(factory, people: People) -> None:
    with factory() as session:
        admin = _user(session, people.admin)
        with pytest.raises(Refused):
            services.set_active(session, admin, admin.id, False)
        with pytest.raises(Refused):
            services.change_role(session, admin, admin.id, "tutor")
        with pytest.raises(Refused):
            services.set_active(session, _user(session, people.tutor), people.student, False)


# --- login throttle ------------------------------------------------------------------------------

PAIR = throttle.PER_ACCOUNT_AND_ADDRESS


def test_the_delay_grows_with_each_failure_and_stops_at_the_maximum() -> None:
    delays = [PAIR.delay_after(n).total_seconds() for n in range(PAIR.free_failures + 12)]
    assert delays[:PAIR.free_failures] == [0] * PAIR.free_failures
    assert delays[PAIR.free_failures:PAIR.free_failures + 4] == [2, 4, 8, 16]
    assert max(delays) == 900 and delays[-1] == 900
    assert PAIR.delay_after(10**6) == PAIR.max_delay


def test_each_try_after_the_free_ones_waits_twice_as_long_unchecked(factory, people: People) -> None:
    with factory() as session:
        create_user(session, "ada", "student", PASSWORD)
        moment = NOW
        for _ in range(PAIR.free_failures):
            assert log_in(session, "ada", "wrong-password!", "10.0.0.1", moment).user is None
        waits = []
        for _ in range(4):
            blocked = log_in(session, "ada", PASSWORD, "10.0.0.1", moment)  # the right password, refused unread
            assert blocked.user is None and blocked.blocked_seconds is not None
            waits.append(blocked.blocked_seconds)
            moment += timedelta(seconds=blocked.blocked_seconds)
            assert log_in(session, "ADA ", "wrong-password!", "10.0.0.1", moment).blocked_seconds is None
        assert waits == [2, 4, 8, 16]
        session.commit()
        assert session.scalar(select(func.count()).select_from(LoginFailure)) == PAIR.free_failures + 4


def test_an_attacker_elsewhere_never_slows_the_owner_from_their_own_address(factory, people: People) -> None:
    with factory() as session:
        create_user(session, "ada", "student", PASSWORD)
        for attacker in range(10):
            for _ in range(8):
                log_in(session, "ada", "wrong-password!", f"203.0.113.{attacker}", NOW)
        session.commit()
        assert log_in(session, "ada", "wrong-password!", "203.0.113.1", NOW).blocked_seconds is not None
        assert log_in(session, "ada", PASSWORD, "10.9.9.9", NOW).user is not None


def test_an_address_failing_on_many_accounts_is_slowed_for_every_account(factory, people: People) -> None:
    with factory() as session:
        create_user(session, "ada", "student", PASSWORD)
        for i in range(throttle.PER_ADDRESS.free_failures):
            log_in(session, f"user{i}", "wrong-password!", "10.0.0.1", NOW)
        session.commit()
        outcome = log_in(session, "ada", PASSWORD, "10.0.0.1", NOW)
        assert outcome.user is None and outcome.blocked_seconds == 2
        assert log_in(session, "ada", PASSWORD, "10.0.0.2", NOW).user is not None
        assert log_in(session, "ada", PASSWORD, "10.0.0.1", NOW + timedelta(seconds=2)).user is not None


def test_a_success_clears_the_accounts_failures_from_that_address_only(factory, people: People) -> None:
    with factory() as session:
        create_user(session, "ada", "student", PASSWORD)
        for address in ("10.0.0.1", "10.0.0.2"):
            for _ in range(2):
                log_in(session, "ada", "wrong-password!", address, NOW)
        log_in(session, "bob", "wrong-password!", "10.0.0.1", NOW)
        assert log_in(session, "ada", PASSWORD, "10.0.0.1", NOW).user is not None
        session.commit()
        left = session.execute(select(LoginFailure.username, LoginFailure.address)).all()
        assert sorted(left) == [("ada", "10.0.0.2"), ("ada", "10.0.0.2"), ("bob", "10.0.0.1")]


def test_admins_see_the_throttled_keys_and_clear_them(factory, people: People) -> None:
    with factory() as session:
        for _ in range(PAIR.free_failures + 1):  # the last try is refused unread, not counted
            log_in(session, "ada", "wrong-password!", "10.0.0.1", NOW)
        for i in range(throttle.PER_ADDRESS.free_failures):
            log_in(session, f"user{i}", "wrong-password!", "10.0.0.7", NOW)
        log_in(session, "bob", "wrong-password!", "10.0.0.1", NOW)  # one failure slows nobody: not listed
        session.commit()
        admin, student = _user(session, people.admin), _user(session, people.student)
        listed = services.login_throttles(session, admin, NOW)
        assert [(t.username, t.address, t.failures) for t in listed] == [
            ("ada", "10.0.0.1", PAIR.free_failures), (None, "10.0.0.7", throttle.PER_ADDRESS.free_failures)]
        assert listed[0].blocked_until == NOW + timedelta(seconds=2)
        assert listed[0].to_dict()["blocked_until"] == "2026-11-23T09:00:02Z"
        with pytest.raises(Refused) as refused:
            services.login_throttles(session, student, NOW)
        assert refused.value.status == 403
        with pytest.raises(Refused):
            services.clear_login_throttle(session, student, "10.0.0.1", "ada")
        assert services.clear_login_throttle(session, admin, "10.0.0.1", "ADA") == PAIR.free_failures
        assert services.clear_login_throttle(session, admin, "10.0.0.7", None) == throttle.PER_ADDRESS.free_failures
        assert services.login_throttles(session, admin, NOW) == []
        assert log_in(session, "ada", "wrong-password!", "10.0.0.1", NOW).blocked_seconds is None


@pytest.mark.parametrize(("address", "username", "field"), [
    (None, "ada", "address"), ("", None, "address"), ("   ", None, "address"), ("x" * 65, None, "address"),
    (["10.0.0.1"], None, "address"), (7, None, "address"), ("10.0.0.1", 5, "username"),
    ("10.0.0.1", "a" * 129, "username"), ("10.0.0.1", {"name": "ada"}, "username"),
])
def test_clearing_a_throttle_names_the_bad_field(factory, people: People, address, username, field) -> None:
    with factory() as session:
        with pytest.raises(InvalidField) as invalid:
            services.clear_login_throttle(session, _user(session, people.admin), address, username)
        assert invalid.value.field == field


def test_failures_older_than_a_day_are_forgotten(factory: sessionmaker[Session], people: People) -> None:
    with factory() as session:
        log_in(session, "ghost", "x", "10.0.0.1", NOW - timedelta(days=2))
        log_in(session, "ghost", "x", "10.0.0.1", NOW)
        session.commit()
        assert session.scalar(select(func.count()).select_from(LoginFailure)) == 1
