"""The HTML reports of compare, diagnose, margins, compensators and a 6-DoF
sweep (the docking envelope), opened in a
real headless chromium: every figure loads, nothing but the page itself and its
data: URIs is requested, and nothing overflows the page horizontally at 1280
and 800 px (a wide table or code block scrolls inside its own box).

Runs only with ``-m browser`` (``make test-browser``; ``pyproject.toml``
deselects the marker otherwise). It drives the system's chromium
(``/usr/bin/chromium``, Debian's package; ``HYBRIDTABLE_CHROMIUM`` names another)
through playwright, and never downloads a browser. Without chromium or
playwright the tests skip, unless ``HYBRIDTABLE_REQUIRE_BROWSER=1`` (set by
``make test-browser``): then they fail.
"""

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.examples import EXAMPLES

pytestmark = pytest.mark.browser

CHROMIUM = os.environ.get("HYBRIDTABLE_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
VIEWPORT_WIDTHS_PX = (1280, 800)

#: The four commands on small inputs (each gets ``--report DIR``).
COMMANDS = {
    "compare": ["compare", str(EXAMPLES)],
    "diagnose": ["diagnose", str(EXAMPLES)],
    "margins": [
        "margins",
        "--sensor-delay-s",
        "0:0.02:5",
        "--table-response-hz",
        "5:100:5",
        "--no-progress",
    ],
    "compensators": ["compensators", "--quick", "--no-progress"],
    # a 6-DoF campaign's envelope (its --out is added in the fixture)
    "sweep": [
        "sweep",
        str(Path(__file__).with_name("docking_envelope_small.toml")),
        "--no-progress",
    ],
}

#: Figures each report has at least (compare: 4 per run, diagnose: 3 per run + 1;
#: the envelope: a map per numeric metric, the CDF, the energy-honesty boundary;
#: its capture boundary is a sentence, no run of the plate capturing).
MIN_FIGURES = {"compare": 12, "diagnose": 10, "margins": 4, "compensators": 3, "sweep": 7}

_RUN_CLI = "import sys; from hybridtable.cli import main; sys.exit(main(sys.argv[1:]))"

# Elements that stick out to the right of the viewport and are not inside a
# box that scrolls horizontally: these are what makes a page scroll sideways.
_OFFENDERS_JS = """() => {
  const w = window.innerWidth;
  const scrolls = (e) => {
    for (let a = e.parentElement; a && a !== document.body; a = a.parentElement) {
      const o = getComputedStyle(a).overflowX;
      if (o === 'auto' || o === 'scroll') return true;
    }
    return false;
  };
  return Array.from(document.body.querySelectorAll('*'))
    .filter((e) => e.getBoundingClientRect().right > w + 0.5 && !scrolls(e))
    .slice(0, 10)
    .map((e) => `${e.tagName.toLowerCase()}.${e.className} right=${e.getBoundingClientRect().right}`);
}"""

_IMAGES_JS = """() => Array.from(document.images).map((i) => ({
  alt: i.alt, complete: i.complete, naturalWidth: i.naturalWidth,
  data: i.src.startsWith('data:image/'), shownWidth: i.getBoundingClientRect().width,
  inFigure: i.closest('figure') !== null,
}))"""


def _unavailable(reason: str) -> None:
    if os.environ.get("HYBRIDTABLE_REQUIRE_BROWSER") == "1":
        pytest.fail(f"{reason} (HYBRIDTABLE_REQUIRE_BROWSER=1)")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def browser():
    """Headless chromium of the system, driven by playwright."""
    if not os.access(CHROMIUM, os.X_OK):
        _unavailable(f"no chromium at {CHROMIUM}")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _unavailable("playwright is not installed (pip install -e '.[browser]')")
    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
        yield b
        b.close()


@pytest.fixture(scope="module")
def reports(browser, tmp_path_factory):
    """Run the commands at once with ``--report``; name -> report folder."""
    root = tmp_path_factory.mktemp("reports")
    env = dict(os.environ, MPLBACKEND="Agg")
    procs, t0 = {}, time.perf_counter()
    for name, argv in COMMANDS.items():
        folder = root / name
        if name == "sweep":
            argv = [*argv, "--out", str(root / "envelope.parquet")]
        log = (root / f"{name}.log").open("w")
        procs[name] = (
            folder,
            log,
            subprocess.Popen(
                [sys.executable, "-c", _RUN_CLI, *argv, "--report", str(folder)],
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
            ),
        )
    for name, (_, log, proc) in procs.items():
        rc = proc.wait(timeout=900)
        log.close()
        assert rc == 0, f"{name} exited with {rc}:\n{(root / f'{name}.log').read_text()[-3000:]}"
    print(f"\nthe commands with --report: {time.perf_counter() - t0:.1f} s (in parallel)")
    return {name: folder for name, (folder, _, _) in procs.items()}


def _markdown(folder: Path) -> Path:
    """The report's Markdown (margins writes ``summary.md``)."""
    return folder / "report.md" if (folder / "report.md").exists() else folder / "summary.md"


@pytest.mark.parametrize("width_px", VIEWPORT_WIDTHS_PX)
@pytest.mark.parametrize("name", list(COMMANDS))
def test_report_opens_whole(browser, reports, name, width_px):
    page_file = reports[name] / "report.html"
    assert page_file.is_file(), f"{name} --report wrote no report.html"
    md = _markdown(reports[name]).read_text()
    md_figures = [line for line in md.splitlines() if re.match(r"!\[[^\]]*\]\([^)]+\)\s*$", line)]
    md_captions = [
        line
        for prev, line in zip(md.splitlines(), md.splitlines()[1:], strict=False)
        if prev in md_figures and re.match(r"\*[^*].*\*\s*$", line)
    ]
    assert len(md_figures) >= MIN_FIGURES[name]

    page = browser.new_page(viewport={"width": width_px, "height": 900})
    requested, errors = [], []
    page.on("request", lambda r: requested.append(r.url))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    try:
        page.goto(page_file.as_uri(), wait_until="load")
        page.wait_for_function(
            "Array.from(document.images).every((i) => i.complete)", timeout=15_000
        )
        images = page.evaluate(_IMAGES_JS)
        scroll_width = page.evaluate("document.documentElement.scrollWidth")
        inner_width = page.evaluate("window.innerWidth")
        offenders = page.evaluate(_OFFENDERS_JS)
        title = page.title()
        captions = page.evaluate(
            "Array.from(document.querySelectorAll('figure figcaption')).length"
        )
    finally:
        page.close()

    # Every figure of the Markdown is on the page, embedded and decoded.
    assert len(images) == len(md_figures)
    assert captions == len(md_captions)
    bad = [i["alt"] for i in images if not (i["complete"] and i["naturalWidth"] > 0)]
    assert not bad, f"figures that did not load: {bad}"
    assert all(i["data"] and i["inFigure"] for i in images)
    assert all(0 < i["shownWidth"] <= inner_width for i in images)
    # Nothing but the page itself and its data: URIs is fetched; no error.
    assert [u for u in requested if not u.startswith(("data:", "file:"))] == []
    assert [u for u in requested if u.startswith("file:")] == [page_file.as_uri()]
    assert errors == []
    # Nothing makes the page scroll sideways.
    assert inner_width == width_px
    assert scroll_width <= inner_width, f"page {scroll_width} px wide: {offenders}"
    assert offenders == []
    # Titled by the report's first heading.
    assert title == re.search(r"^# (.+)$", md, re.M).group(1).strip()
