"""The Meshcat recording of a 6-DoF run (``simulate6 --html``), opened in a real
headless chromium: it loads from the file alone, without a JavaScript error,
and draws into a WebGL canvas.

Runs only with ``-m browser`` (see ``test_reports_in_browser.py``, whose
``browser`` fixture it shares: the system's chromium through playwright, a
skip without them unless ``HYBRIDTABLE_REQUIRE_BROWSER=1``).
"""

import math

import pytest

from tests.browser.test_reports_in_browser import browser  # noqa: F401  (the fixture)

pytestmark = pytest.mark.browser


def test_docking_recording_loads_and_draws_into_a_canvas(browser, tmp_path):  # noqa: F811
    from hybridtable.six_dof.simulation import simulate6
    from hybridtable.six_dof.view import write_docking_html
    from tests.six_dof.conftest import docking_params

    params = docking_params(
        pitch_deg=math.degrees(0.035),
        duration_s=0.2,
        table_response_hz=25.0,
        sensor_delay_s=0.005,
        compensator="SDMDC",
    )
    page_file = tmp_path / "docking.html"
    info = write_docking_html(simulate6(params), page_file)
    assert info["frames"] == 13

    page = browser.new_page(viewport={"width": 1000, "height": 700})
    requested, errors = [], []
    page.on("request", lambda r: requested.append(r.url))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    try:
        page.goto(page_file.as_uri(), wait_until="load")
        page.wait_for_function("document.querySelectorAll('canvas').length > 0", timeout=15_000)
        page.wait_for_timeout(500)  # a few animation frames
        canvases = page.evaluate(
            """() => Array.from(document.querySelectorAll('canvas')).map((c) => ({
              w: c.getBoundingClientRect().width, h: c.getBoundingClientRect().height,
              webgl: !!(c.getContext('webgl2') || c.getContext('webgl')),
            }))"""
        )
    finally:
        page.close()

    assert errors == []
    # Nothing but the page itself and its data: URIs is fetched.
    assert [u for u in requested if not u.startswith(("data:", "file:"))] == []
    assert [u for u in requested if u.startswith("file:")] == [page_file.as_uri()]
    # The scene's canvas fills the page and is a WebGL context.
    scene = max(canvases, key=lambda c: c["w"] * c["h"])
    assert scene["w"] == 1000 and scene["h"] == 700
    assert scene["webgl"]
