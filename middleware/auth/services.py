"""Account rules: creating accounts, checking passwords. No Flask request state in here."""

from __future__ import annotations

import functools
import secrets
from dataclasses import dataclass
from datetime import datetime

from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session
from werkzeug.security import check_password_hash, generate_password_hash

from middleware.auth import throttle
from middleware.auth.schemas import InvalidField, clean_new_password, clean_role, clean_username
from middleware.models import Role, User

# scrypt is a memory-hard KDF; werkzeug salts it and encodes the parameters in the hash.
PASSWORD_METHOD = "scrypt"


@functools.cache
def _timing_equaliser(method: str) -> str:
    """Checking a password for an unknown username still costs one hash of the method's cost, so timing does not
    reveal accounts (made on first use: a process that never checks a password, such as a writer child, makes none)."""
    return generate_password_hash("telelab-timing-equaliser", method=method)


def make_timing_equaliser() -> None:
    """Makes the unknown-username hash now (create_app), so that a first failed login costs one hash as any other."""
    _timing_equaliser(PASSWORD_METHOD)


class AccountExists(ValueError):
    """The username is taken."""


def generate_password() -> str:
    """A random password that is easy to type from a printout (about 100 bits), starting with a letter or digit:
    CSV downloads quote a cell starting with '-' against formula injection, which would change the password."""
    while True:
        password = "-".join(secrets.token_urlsafe(6) for _ in range(3))
        if password[0].isalnum():
            return password


def create_user(session: Session, username: str, role: str | Role, password: str) -> User:
    """Adds an account after validating every field; the caller commits."""
    clean_name = clean_username(username)
    clean_password = clean_new_password(password)
    user_role = clean_role(role)
    if session.scalar(select(User.id).where(User.username == clean_name)) is not None:
        raise AccountExists(f"An account named {clean_name!r} already exists.")
    user = User(
        username=clean_name,
        role=user_role.value,
        password_hash=generate_password_hash(clean_password, method=PASSWORD_METHOD),
    )
    session.add(user)
    session.flush()
    return user


def set_password(session: Session, username: str, password: str) -> User:
    """Replaces an account's password; the caller commits."""
    user = find_user(session, username)
    if user is None:
        raise InvalidField("username", gettext("There is no account named %(username)s.", username=repr(username)))
    user.password_hash = generate_password_hash(clean_new_password(password), method=PASSWORD_METHOD)
    return user


def find_user(session: Session, username: str) -> User | None:
    """The account with that username, if any."""
    try:
        name = clean_username(username)
    except InvalidField:
        return None
    return session.scalar(select(User).where(User.username == name))


def matching_account(session: Session, username: str, password: str) -> User | None:
    """The account whose password matches, active or disabled, or None; costs one hash either way."""
    user = find_user(session, username)
    if user is None:
        check_password_hash(_timing_equaliser(PASSWORD_METHOD), password)
        return None
    return user if check_password_hash(user.password_hash, password) else None


def authenticate(session: Session, username: str, password: str) -> User | None:
    """The active account whose password matches, or None; costs one hash either way."""
    user = matching_account(session, username, password)
    return user if user is not None and user.is_active else None


@dataclass(frozen=True)
class LoginOutcome:
    """The answer to a login attempt: the user, or why not (blocked_seconds when slowed by the throttle)."""

    user: User | None
    blocked_seconds: int | None = None
    disabled: bool = False  # the password was right but the account is disabled (told only to who knows it)


def log_in(session: Session, username: str, password: str, address: str, now: datetime) -> LoginOutcome:
    """Checks a login under the throttle; a failure is recorded, a success clears this address's failures for the
    account. The caller commits."""
    blocked = throttle.seconds_blocked(session, username, address, now)
    if blocked is not None:
        return LoginOutcome(None, blocked)
    account = matching_account(session, username, password)
    if account is None or not account.is_active:
        throttle.record_failure(session, username, address, now)
        return LoginOutcome(None, disabled=account is not None)
    throttle.record_success(session, username, address)
    return LoginOutcome(account)


def hash_password(password: str) -> str:
    """The scrypt hash of a password that already passed validation."""
    return generate_password_hash(password, method=PASSWORD_METHOD)


def change_own_password(session: Session, user: User, current_password: str, new_password: str) -> None:
    """Replaces the user's password when current_password is right; the caller commits."""
    if not check_password_hash(user.password_hash, current_password or ""):
        raise InvalidField("current_password", gettext("Your current password is not right. Type it again."))
    clean = clean_new_password(new_password)
    if clean == current_password:
        raise InvalidField("new_password", gettext("Choose a new password different from the current one."))
    user.password_hash = hash_password(clean)
