"""Validation of account fields coming from forms, the CLI and files."""

from __future__ import annotations

import re

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.errors import Refused
from middleware.models import Role

USERNAME_PATTERN = re.compile(r"^[a-z0-9][a-z0-9._-]{1,63}$")
MIN_PASSWORD_LENGTH = 10
MAX_PASSWORD_LENGTH = 256


class InvalidField(Refused, ValueError):
    """A value refused by validation (400 invalid_field); field names the input and the message says what is
    allowed."""

    field: str

    def __init__(self, field: str, message: str) -> None:
        super().__init__(400, "invalid_field", message, field)


def clean_username(value: object) -> str:
    """A username: 2-64 lowercase letters, digits, '.', '_' or '-', starting with a letter or digit."""
    if not isinstance(value, str):
        raise InvalidField("username", gettext("username must be text."))
    username = value.strip().lower()
    if not USERNAME_PATTERN.fullmatch(username):
        raise InvalidField(
            "username",
            gettext("username must be 2 to 64 characters: lowercase letters, digits, '.', '_' or '-'."),
        )
    return username


def clean_role(value: object) -> Role:
    """One of the known roles."""
    try:
        return Role(str(value).strip().lower())
    except ValueError:
        allowed = ", ".join(r.value for r in Role)
        raise InvalidField("role", gettext("role must be one of: %(allowed)s.", allowed=allowed)) from None


def clean_new_password(value: object) -> str:
    """A password long enough to resist guessing and short enough to hash cheaply."""
    if not isinstance(value, str) or not (MIN_PASSWORD_LENGTH <= len(value) <= MAX_PASSWORD_LENGTH):
        raise InvalidField(
            "password",
            gettext("password must be between %(low)s and %(high)s characters.", low=MIN_PASSWORD_LENGTH,
                    high=MAX_PASSWORD_LENGTH),
        )
    return value
