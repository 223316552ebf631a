"""Generated passwords leave the enrolment CSV download exactly as they were made (a leading '-', about 1 in 64
before, was quoted against formula injection and the printed password failed)."""

from __future__ import annotations

import csv
import io

from middleware.auth.services import generate_password
from middleware.courses.schemas import report_csv


def test_generated_passwords_survive_the_csv_download_unchanged() -> None:
    created = [(f"user{i}", generate_password()) for i in range(2000)]  # P(no leading '-' in 2000) was ~1e-14
    rows = list(csv.DictReader(io.StringIO(report_csv([], created, []))))
    assert [row["password"] for row in rows] == [password for _name, password in created]
