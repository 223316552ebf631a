"""Account rules: who may list, create, disable, re-role and reset whom. No Flask request state in here.

Admins manage every account. A tutor may reset the password of a student enrolled in a course the
tutor teaches, and nothing else. Every function takes the acting user and raises Refused when the
actor may not; the caller commits.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import exists, func, select
from sqlalchemy.orm import Session, aliased

from middleware.accounts.schemas import clean_throttle_key
from middleware.auth import throttle
from middleware.auth.schemas import InvalidField, clean_role, clean_username
from middleware.auth.services import AccountExists, create_user, generate_password, hash_password
from middleware.errors import Refused
from middleware.models import CourseMembership, Role, User


def forbidden(message: str | None = None) -> Refused:
    """A 403 refusal (message: said through gettext)."""
    return Refused(403, "forbidden", message or gettext("You are not allowed to do that."))


def require_admin(actor: User) -> None:
    """Refuses anyone but an admin."""
    if actor.role != Role.ADMIN:
        raise forbidden(gettext("Only an admin can do that."))


def get_user(session: Session, user_id: int) -> User:
    """The account with that id, or a 404 refusal."""
    user = session.get(User, user_id)
    if user is None:
        raise Refused(404, "unknown_user", gettext("There is no account with id %(user_id)s.", user_id=user_id),
                                           "user_id")
    return user


def is_course_tutor(session: Session, user_id: int, course_id: int | None) -> bool:
    """True when user_id is a tutor member of the course (never for no course)."""
    if course_id is None:
        return False
    return session.execute(select(func.count()).select_from(CourseMembership).where(
        CourseMembership.course_id == course_id, CourseMembership.user_id == user_id,
        CourseMembership.role == "tutor")).scalar_one() > 0


def tutors_student(session: Session, tutor_id: int, student_id: int) -> bool:
    """True when the student is enrolled as a student in a course where tutor_id is a tutor."""
    mine, theirs = aliased(CourseMembership), aliased(CourseMembership)
    return bool(session.scalar(select(exists().where(
        mine.user_id == tutor_id, mine.role == "tutor", theirs.course_id == mine.course_id,
        theirs.user_id == student_id, theirs.role == "student"))))


def may_reset_password(session: Session, actor: User, target: User) -> bool:
    """Admins reset anyone's password; tutors only their own students'."""
    if actor.role == Role.ADMIN:
        return True
    return (actor.role == Role.TUTOR and target.role == Role.STUDENT
            and tutors_student(session, actor.id, target.id))


@dataclass(frozen=True)
class UserView:
    """An account as the admin pages and the API show it."""

    id: int
    username: str
    role: str
    is_active: bool

    def to_dict(self) -> dict[str, object]:
        """The JSON form."""
        return {"id": self.id, "username": self.username, "role": self.role, "is_active": self.is_active}


def list_users(session: Session, actor: User) -> list[UserView]:
    """Every account, by username (admins only)."""
    require_admin(actor)
    return [UserView(u.id, u.username, u.role, u.is_active)
            for u in session.scalars(select(User).order_by(User.username))]


def create_account(session: Session, actor: User, username: object, role: object) -> tuple[User, str]:
    """Creates an account with a generated password (admins only); returns it and the password, shown once."""
    require_admin(actor)
    password = generate_password()
    name, user_role = clean_username(username), clean_role(role)
    try:
        return create_user(session, name, user_role, password), password
    except AccountExists as error:
        raise Refused(409, "account_exists", gettext("An account named %(name)s already exists.", name=repr(name)),
                      "username") from error


def set_active(session: Session, actor: User, user_id: int, active: bool) -> User:
    """Disables or enables an account (admins only; not their own). A disabled user's session ends."""
    require_admin(actor)
    user = get_user(session, user_id)
    if user.id == actor.id and not active:
        raise Refused(409, "own_account", gettext("You cannot disable your own account."), "is_active")
    user.is_active = active
    return user


def change_role(session: Session, actor: User, user_id: int, role: object) -> User:
    """Gives an account another role (admins only; an admin cannot demote themself)."""
    require_admin(actor)
    user = get_user(session, user_id)
    new_role = clean_role(role)
    if user.id == actor.id and new_role != Role.ADMIN:
        raise Refused(409, "own_account", gettext("You cannot take the admin role from your own account."), "role")
    user.role = new_role.value
    return user


def reset_password(session: Session, actor: User, user_id: int) -> tuple[User, str]:
    """Gives the account a generated password, shown once; admins, or a tutor for their students."""
    target = get_user(session, user_id)
    if not may_reset_password(session, actor, target):
        raise forbidden(gettext("You can reset passwords only of students in the courses you teach."))
    if target.id == actor.id:
        raise Refused(409, "own_account", gettext("Change your own password on the password page instead."), "user_id")
    password = generate_password()
    target.password_hash = hash_password(password)
    return target, password


def set_active_by_name(session: Session, username: str, active: bool) -> User:
    """Disables or enables an account by name (the CLI, which acts as the machine's owner)."""
    user = session.scalar(select(User).where(User.username == clean_username(username)))
    if user is None:
        raise InvalidField("username", gettext("There is no account named %(username)s.", username=repr(username)))
    user.is_active = active
    return user


def login_throttles(session: Session, actor: User, now: datetime) -> list[throttle.Throttle]:
    """The login keys being slowed (admins only)."""
    require_admin(actor)
    return throttle.list_throttles(session, now)


def clear_login_throttle(session: Session, actor: User, address: object, username: object) -> int:
    """Forgets the failed logins from an address (of one username, when given); admins only. Returns how many."""
    require_admin(actor)
    clean_address, clean_name = clean_throttle_key(address, username)
    return throttle.clear(session, clean_address, clean_name)
