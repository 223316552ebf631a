"""The xAPI 1.0.3 statement schema (middleware/analytics/xapi-statement.schema.json) accepts the specification's
kinds of statement and refuses each rule of Part Two, section 2.4 broken one at a time."""

from __future__ import annotations

import copy
from typing import Any

import pytest

from middleware.analytics.xapi_schema import statement_errors

AGENT = {"objectType": "Agent", "name": "Project Tin Can API", "mbox": "mailto:user@example.com"}
# The specification's "simple statement" (Part Two, Appendix A), with a result and context added.
SIMPLE: dict[str, Any] = {
    "id": "fd41c918-b88b-4b20-a0a5-a4c32391aaa0", "timestamp": "2015-11-18T12:17:00+00:00", "actor": AGENT,
    "verb": {"id": "http://example.com/xapi/verbs#sent-a-statement", "display": {"en-US": "sent"}},
    "object": {"id": "http://example.com/xapi/activity/simplestatement",
               "definition": {"name": {"en-US": "simple statement"},
                              "description": {"en-US": "A simple Experience API statement."}}},
    "result": {"score": {"scaled": 0.95, "raw": 95, "min": 0, "max": 100}, "success": True, "completion": True,
               "duration": "PT1H0M0S", "extensions": {"http://example.com/profiles/meetings/resultextensions/x": 1}},
    "context": {"registration": "ec531277-b57b-4c15-8d91-d292c5b2b8f7", "platform": "Example virtual meeting",
                "language": "en-GB", "instructor": AGENT,
                "contextActivities": {"parent": [{"objectType": "Activity", "id": "http://www.example.com/meetings/series/267"}],
                                      "category": {"id": "http://www.example.com/meetings/categories/teammeeting"}}},
    "version": "1.0.3",
}
GROUP = {"objectType": "Group", "name": "Team PB", "member": [
    {"name": "Andrew Downes", "account": {"homePage": "http://www.example.com", "name": "13936749"}},
    {"name": "Toby Nichols", "openid": "http://toby.openid.example.org/"},
    {"name": "Ena Hills", "mbox_sha1sum": "ebd31e95054c018b10727ccffd2ef2ec3a016ee9"}]}


def test_the_specifications_kinds_of_statement_are_valid() -> None:
    assert statement_errors(SIMPLE) == []
    by_group = {**SIMPLE, "actor": GROUP}
    assert statement_errors(by_group) == []
    about_a_statement = {**SIMPLE, "object": {"objectType": "StatementRef",
                                              "id": "8f87ccde-bb56-4c2e-ab83-44982ef22df0"}}
    del about_a_statement["context"]  # revision and platform belong to Activities only
    assert statement_errors(about_a_statement) == []
    sub = {**SIMPLE, "context": {"language": "en"}, "object": {
        "objectType": "SubStatement", "actor": AGENT, "verb": {"id": "http://example.com/visited"},
        "object": {"objectType": "Activity", "id": "http://example.com/website"}}}
    assert statement_errors(sub) == []
    interaction = {**SIMPLE, "object": {"id": "http://adlnet.gov/expapi/activities/example", "definition": {
        "type": "http://adlnet.gov/expapi/activities/cmi.interaction", "interactionType": "choice",
        "correctResponsesPattern": ["golf[,]tetris"],
        "choices": [{"id": "golf", "description": {"en-US": "Golf Example"}}, {"id": "tetris"}]}}}
    assert statement_errors(interaction) == []
    attached = {**SIMPLE, "attachments": [{"usageType": "http://adlnet.gov/expapi/attachments/signature",
                                           "display": {"en-US": "Signature"}, "contentType": "application/octet-stream",
                                           "length": 4235,
                                           "sha2": "672fa5fa658017f1b72d65036f13379c6ab05d4ab3b6664908d8acf0b6a0c634"}]}
    assert statement_errors(attached) == []


def broken(change) -> dict[str, Any]:
    statement = copy.deepcopy(SIMPLE)
    change(statement)
    return statement


@pytest.mark.parametrize("why, change", [
    ("no actor", lambda s: s.pop("actor")),
    ("no verb", lambda s: s.pop("verb")),
    ("no object", lambda s: s.pop("object")),
    ("two identifiers of one agent", lambda s: s["actor"].update(openid="http://a.example/")),
    ("an agent with no identifier", lambda s: s["actor"].pop("mbox")),
    ("an mbox that is not a mailto IRI", lambda s: s["actor"].update(mbox="user@example.com")),
    ("an account without its homePage", lambda s: s.update(actor={"account": {"name": "1"}})),
    ("a verb id that is not an IRI", lambda s: s["verb"].update(id="sent")),
    ("a language map keyed by no language tag", lambda s: s["verb"].update(display={"english language!": "x"})),
    ("an activity without its id", lambda s: s["object"].pop("id")),
    ("an unknown interaction type", lambda s: s["object"]["definition"].update(interactionType="essay")),
    ("a scaled score above 1", lambda s: s["result"]["score"].update(scaled=1.5)),
    ("a raw score above max", lambda s: s["result"]["score"].update(raw=101)),
    ("a raw score below min", lambda s: s["result"]["score"].update(raw=-1)),
    ("min not below max", lambda s: s["result"]["score"].update(min=100)),
    ("a duration not in ISO 8601", lambda s: s["result"].update(duration="3600 s")),
    ("an id that is not a UUID", lambda s: s.update(id="statement-1")),
    ("a timestamp with the -00:00 offset", lambda s: s.update(timestamp="2015-11-18T12:17:00-00:00")),
    ("a timestamp that is not ISO 8601", lambda s: s.update(timestamp="18/11/2015 12:17")),
    ("a version other than 1.0.x", lambda s: s.update(version="2.0.0")),
    ("a property the statement does not have", lambda s: s.update(grade="A")),
    ("platform with an agent as the object",
     lambda s: s.update(object={"objectType": "Agent", "mbox": "mailto:a@b.c"})),
    ("a sub-statement inside a sub-statement", lambda s: s.update(context={}, object={
        "objectType": "SubStatement", "actor": AGENT, "verb": {"id": "http://e.x/v"},
        "object": {"objectType": "SubStatement", "actor": AGENT, "verb": {"id": "http://e.x/v"},
                   "object": {"id": "http://e.x/a"}}})),
    ("an extension keyed by no IRI", lambda s: s["result"].update(extensions={"commands": 3})),
    ("a registration that is not a UUID", lambda s: s["context"].update(registration="42")),
])
def test_each_broken_rule_is_refused(why: str, change) -> None:
    assert statement_errors(broken(change)), why
