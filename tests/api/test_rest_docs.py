"""The REST API's reference page as a browser shows it, without internet: Swagger UI from
the PADT's own files lists the operations."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.browser import chromium
from tests.support.rest_plant import Plant, plant

pytestmark = pytest.mark.browser


@pytest.fixture
def site(tmp_path: Path) -> Iterator[Plant]:
    with plant(tmp_path) as found:
        yield found


def test_the_docs_page_renders_offline(site: Plant, tmp_path: Path) -> None:
    with chromium() as browser:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        requests: list[str] = []
        page.on("request", lambda request: requests.append(request.url))
        page.goto(f"{site.url}/docs")
        page.get_by_text("PADT REST API", exact=False).first.wait_for(timeout=20_000)
        page.get_by_text("/api/resources/{resource}/status").first.wait_for(timeout=20_000)
        page.screenshot(path=str(tmp_path / "docs.png"))
    assert all(url.startswith(site.url) for url in requests), [
        url for url in requests if not url.startswith(site.url)
    ]
