"""The tool's own RSA key pairs: generated on first need, rotated by an admin, served as a JWKS.

The newest unretired key signs (deep-link responses, service-token requests); every unretired key stays in the
JWKS, so a platform that cached the old one still checks what was signed with it until the admin retires it.
"""

from __future__ import annotations

import json
from datetime import datetime
from typing import Any

from flask_babel import gettext  # type: ignore[import-untyped]
from jwcrypto.jwk import JWK  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.errors import Refused
from middleware.models.accounts import utc_now
from middleware.models.lti import LtiToolKey

KEY_BITS = 2048


def _new_key(now: datetime) -> LtiToolKey:
    key = JWK.generate(kty="RSA", size=KEY_BITS)
    public_pem = key.export_to_pem().decode()
    return LtiToolKey(kid=key.thumbprint(), private_pem=key.export_to_pem(private_key=True, password=None).decode(),
                      public_pem=public_pem, created_at=now)


def live_keys(session: Session) -> list[LtiToolKey]:
    """The unretired keys, newest first."""
    return list(session.scalars(select(LtiToolKey).where(LtiToolKey.retired_at.is_(None))
                                .order_by(LtiToolKey.created_at.desc(), LtiToolKey.id.desc())))


def signing_key(session: Session) -> LtiToolKey:
    """The key that signs now, made on first need."""
    keys = live_keys(session)
    if keys:
        return keys[0]
    key = _new_key(utc_now())
    session.add(key)
    session.flush()
    return key


def rotate(session: Session) -> LtiToolKey:
    """A new signing key; the previous ones stay in the JWKS until retired."""
    key = _new_key(utc_now())
    session.add(key)
    session.flush()
    return key


def retire(session: Session, kid: str) -> LtiToolKey:
    """Takes a key out of the JWKS; the signing key cannot be retired (rotate first)."""
    key = session.scalar(select(LtiToolKey).where(LtiToolKey.kid == kid, LtiToolKey.retired_at.is_(None)))
    if key is None:
        raise Refused(404, "unknown_key", gettext("There is no key in use with that id."), "kid")
    if key.id == signing_key(session).id:
        raise Refused(409, "signing_key", gettext("That key signs now: rotate to a new key first, then retire this "
                                                  "one."), "kid")
    key.retired_at = utc_now()
    session.flush()
    return key


def public_jwk(key: LtiToolKey) -> dict[str, Any]:
    """The public half of key as a JWK, with its kid, alg and use."""
    jwk = json.loads(JWK.from_pem(key.public_pem.encode()).export_public())
    jwk.update({"kid": key.kid, "alg": "RS256", "use": "sig"})
    return jwk


def jwks(session: Session) -> dict[str, Any]:
    """The key set platforms fetch: every unretired key (one is made on first need)."""
    signing_key(session)
    return {"keys": [public_jwk(key) for key in live_keys(session)]}
