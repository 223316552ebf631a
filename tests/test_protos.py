"""The committed generated modules are exactly what `make protos` produces from the .proto sources."""

from __future__ import annotations

from pathlib import Path

from protos.generate import REPO_ROOT, generate, proto_sources


def test_generated_code_matches_the_proto_sources(tmp_path: Path) -> None:
    generate(tmp_path)
    produced = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    assert produced, "protoc produced nothing"
    for relative in produced:
        committed = REPO_ROOT / relative
        assert committed.exists(), f"{relative} is generated but not committed: run `make protos`"
        assert committed.read_bytes() == (tmp_path / relative).read_bytes(), (
            f"{relative} differs from its .proto: run `make protos` and commit the result"
        )
    assert {p.with_suffix("") for p in proto_sources()}


def test_every_rpc_of_the_contract_is_generated() -> None:
    from protos.telelab.v1 import robot_pb2

    service = robot_pb2.DESCRIPTOR.services_by_name["Robot"]
    assert {m.name for m in service.methods} >= {
        "GetRobotInfo", "ListSkills", "SetController", "Drive", "StreamTelemetry", "StreamCamera", "GetScene",
    }
