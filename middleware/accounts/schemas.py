"""Validation of account, invitation and robot fields from forms and JSON; errors name the field."""

from __future__ import annotations

import re
from datetime import timedelta

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.auth.schemas import InvalidField
from middleware.auth.throttle import MAX_ADDRESS_LENGTH, MAX_USERNAME_LENGTH
from middleware.validation import decimal_int

ROBOT_NAME = re.compile(r"^[A-Za-z0-9_-]{1,32}$")
ROBOT_ADDRESS = re.compile(r"^[A-Za-z0-9.\-\[\]:]{1,250}:[0-9]{1,5}$")
INVITATION_DAYS_DEFAULT = 7
INVITATION_DAYS_MAX = 30
MAX_ID = 2**31 - 1


def clean_id(value: object, field: str) -> int:
    """A positive whole number (from JSON or a form field)."""
    value = decimal_int(value, 1, MAX_ID)
    if value is None:
        raise InvalidField(field, gettext("%(field)s must be a positive whole number.", field=field))
    return value


def clean_optional_id(value: object, field: str) -> int | None:
    """clean_id, or None when absent or empty."""
    return None if value is None or value == "" else clean_id(value, field)


def clean_flag(value: object, field: str) -> bool:
    """A yes/no value: JSON true/false, or the form values '1'/'0', 'true'/'false', 'on'."""
    if isinstance(value, bool):
        return value
    if isinstance(value, str) and value.strip().lower() in {"1", "true", "on", "yes"}:
        return True
    if isinstance(value, str) and value.strip().lower() in {"0", "false", "off", "no"}:
        return False
    raise InvalidField(field, gettext("%(field)s must be true or false.", field=field))


def clean_robot_name(value: object) -> str:
    """A robot name usable in URLs: 1-32 letters, digits, '-' or '_'."""
    if not isinstance(value, str) or not ROBOT_NAME.fullmatch(value.strip()):
        raise InvalidField("name", gettext("name must be 1 to 32 letters, digits, '-' or '_' (it appears in "
                                           "addresses)."))
    return value.strip()


def clean_robot_kind(value: object) -> str:
    """A robot kind (the pool it serves in): 1-32 letters, digits, '-' or '_', like a robot name."""
    if not isinstance(value, str) or not ROBOT_NAME.fullmatch(value.strip()):
        raise InvalidField("kind", gettext("kind must be 1 to 32 letters, digits, '-' or '_' (robots of one kind "
                                           "form a pool)."))
    return value.strip()


def clean_robot_title(value: object) -> str:
    """A title for people: 1-100 characters on one line."""
    if not isinstance(value, str) or not value.strip() or len(value.strip()) > 100 or not value.isprintable():
        raise InvalidField("title", gettext("title must be 1 to 100 characters on one line."))
    return value.strip()


def clean_robot_address(value: object) -> str:
    """host:port of a skill server, port 1-65535."""
    if not isinstance(value, str) or not ROBOT_ADDRESS.fullmatch(value.strip()):
        raise InvalidField("address", gettext("address must look like 'robot-host:50051' (a host name or IP, and a "
                                              "port)."))
    port = int(value.strip().rsplit(":", 1)[1])
    if not 1 <= port <= 65535:
        raise InvalidField("address", gettext("the port in address must be between 1 and 65535."))
    return value.strip()


def clean_invitation_days(value: object) -> timedelta:
    """How long an invitation link lasts: 1-30 days (default 7)."""
    if value is None or value == "":
        return timedelta(days=INVITATION_DAYS_DEFAULT)
    value = decimal_int(value, 1, INVITATION_DAYS_MAX)
    if value is None:
        raise InvalidField("days", gettext("days must be a whole number from 1 to %(invitation_days_max)s.",
                                           invitation_days_max=INVITATION_DAYS_MAX))
    return timedelta(days=value)


def clean_throttle_key(address: object, username: object) -> tuple[str, str | None]:
    """A login throttle's key from a form or JSON: an address (required) and, optionally, a username."""
    if not isinstance(address, str) or not address.strip() or len(address.strip()) > MAX_ADDRESS_LENGTH:
        raise InvalidField("address", gettext("address must be the address shown in the list (1 to "
                                              "%(max_address_length)s characters).",
                                              max_address_length=MAX_ADDRESS_LENGTH))
    if username is None or username == "":
        return address.strip(), None
    if not isinstance(username, str) or len(username) > MAX_USERNAME_LENGTH:
        raise InvalidField("username", gettext("username must be text of at most %(max_username_length)s "
                                               "characters, or left out to clear the whole address.",
                                               max_username_length=MAX_USERNAME_LENGTH))
    return address.strip(), username
