"""Bad input against the REST API: schemathesis generates requests from the OpenAPI
description (valid and invalid bodies, paths and parameters) for every operation and sends
them to the real server, logged in as Read+Write and to the resource as its
Administrator, so the requests reach the runtime. No reply may be a server error, and the
resource must keep answering and cycling afterwards."""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Iterator
from typing import Any

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from schemathesis.checks import not_a_server_error

from tests.support.rest_plant import Plant, plant

# path parameters that exist in the plant, used for about half the cases: random names
# alone would only ever meet "no such resource"
KNOWN = st.fixed_dictionaries(
    {
        "resource": st.just("Plant"),
        "program": st.just("P"),
        "project": st.sampled_from(["plant", "plant_v2"]),
        "variable": st.sampled_from(["P.n", "P.limit", "P.flag"]),
        "name": st.sampled_from(
            ["watchdog_ms", "target_cycle_ms", "target_cycle_mode", "com_slice_ms"]
        ),
    }
)


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Plant]:
    with plant(tmp_path_factory.mktemp("fuzz")) as found:
        yield found


@pytest.fixture(scope="module")
def authorization(site: Plant) -> dict[str, str]:
    return {"Authorization": f"Bearer {site.session('builder', 'admin')}"}


def fuzz(operation: Any, authorization: dict[str, str], examples: int) -> Counter[int]:
    """Send `examples` generated cases of one operation; the HTTP statuses they got."""
    statuses: Counter[int] = Counter()

    @given(case=operation.as_strategy(), known=st.none() | KNOWN)
    @settings(
        max_examples=examples,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    )
    def no_server_error(case: schemathesis.Case[Any], known: dict[str, str] | None) -> None:
        if known is not None:
            path = case.path_parameters or {}
            case.path_parameters = {k: known.get(k, v) for k, v in path.items()}
            if isinstance(case.body, dict) and "project" in case.body:
                case.body["project"] = known["project"]
        response = case.call_and_validate(headers=authorization, checks=[not_a_server_error])
        statuses[response.status_code] += 1

    no_server_error()
    return statuses


# every run sends some cases of each operation; the slow run (-m slow) many more
@pytest.mark.parametrize("examples", [6, pytest.param(40, marks=pytest.mark.slow)])
def test_no_request_gets_a_server_error(
    site: Plant, authorization: dict[str, str], examples: int
) -> None:
    # logging out would end the session the rest of the run uses
    schema = schemathesis.openapi.from_url(f"{site.url}/openapi.json").exclude(
        path_regex=r".*/logout$"
    )
    operations = [result.ok() for result in schema.get_all_operations()]  # type: ignore[union-attr]
    assert len(operations) >= 30
    answered = {op.label: fuzz(op, authorization, examples) for op in operations}
    # the generated requests got past validation into the resource, and were refused too
    succeeded = sorted(label for label, statuses in answered.items() if statuses[200])
    print(f"{len(succeeded)} of {len(answered)} operations answered 200 at least once")
    for label, statuses in sorted(answered.items()):
        print(f"  {label}: {dict(sorted(statuses.items()))}")
    assert len(succeeded) >= len(answered) // 3
    assert sum(statuses[400] + statuses[404] + statuses[409] for statuses in answered.values())


def test_the_resource_kept_answering_and_cycling(site: Plant) -> None:
    """The fuzz may legitimately have stopped it, or set a watchdog so short that a
    hiccup of the machine ended in ERROR STOP: from any of these it starts again."""
    token = site.session("builder", "admin")
    status = site.call("GET", "/api/resources/Plant/status", token).json()
    if status["state"] == "ERROR STOP":
        assert site.call("POST", "/api/resources/Plant/init", token).status_code == 200
    for name, value in (("watchdog_ms", 200), ("target_cycle_ms", 20)):
        site.call("PUT", f"/api/resources/Plant/parameters/{name}", token, json={"value": value})
    if site.call("GET", "/api/resources/Plant/status", token).json()["state"] != "RUN":
        started = site.call("POST", "/api/resources/Plant/start", token)
        assert started.status_code == 200, started.text
    first = site.call("GET", "/api/resources/Plant/status", token).json()["cycle"]
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        later = site.call("GET", "/api/resources/Plant/status", token).json()
        if later["cycle"] > first + 5:
            break
        time.sleep(0.05)
    assert later["state"] == "RUN" and later["cycle"] > first + 5
