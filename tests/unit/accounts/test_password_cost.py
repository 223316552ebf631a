"""The product hashes passwords with scrypt at werkzeug's default cost: the suite's own cheaper hashes (tests/
conftest.py) must never be what a lab stores."""

from __future__ import annotations

from werkzeug.security import check_password_hash, generate_password_hash


def test_the_product_hashes_passwords_with_scrypt_at_its_full_cost(product_password_method: str) -> None:
    stored = generate_password_hash("correct-horse-battery", method=product_password_method)
    assert stored.startswith("scrypt:32768:8:1$"), stored
    assert check_password_hash(stored, "correct-horse-battery")
