"""The HTML page of a report (hybridtable.reports.html): made from the report's
Markdown, loading nothing from outside itself, figures with their captions."""

import base64
import re
from html.parser import HTMLParser

import matplotlib.pyplot as plt
import pytest

from hybridtable.reports.html import HTML_NAME, markdown_to_html, write_html_report


class _Page(HTMLParser):
    """Tags with their attributes, in document order, and the text of each
    figcaption and title."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str]]] = []
        self.stack: list[str] = []
        self.text: dict[str, list[str]] = {"figcaption": [], "title": [], "figure": []}

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        self.stack.append(tag)
        if tag in self.text:
            self.text[tag].append("")

    def handle_endtag(self, tag):
        while self.stack and self.stack.pop() != tag:
            pass

    def handle_data(self, data):
        for tag in self.text:
            if tag in self.stack:
                self.text[tag][-1] += data

    def all(self, tag: str) -> list[dict[str, str]]:
        return [a for t, a in self.tags if t == tag]


def _parse(page: str) -> _Page:
    p = _Page()
    p.feed(page)
    return p


def _png(path, width_in: float = 2.0) -> bytes:
    fig, ax = plt.subplots(figsize=(width_in, 1.5))
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel("time [s]")
    ax.set_ylabel("force [N]")
    fig.savefig(path, dpi=50)
    plt.close(fig)
    return path.read_bytes()


REPORT = """# Model against measured runs

A sentence with `code` and **bold**.

```
run              comp     f_mea rms/noise [N]   p_act rms/noise [um]  CoR meas CoR model
nominal-run1     none     2.01/2.04   x0.98     1.95/1.87   x1.05    1.17477   1.17521
```

## run-a

| channel | RMS error | noise RMS |
| --- | --- | --- |
| replay f_mea_n | 2.008 N | 2.041 N |
| replay p_act_m | 1.954 um | 1.865 um |

![Force overlay](a.png)
*Measured and modelled force [N] against time [s], run-a.*

![Residuals](b.png)

![Staircase](c.png)
*Error over the noise [1] per model, `nominal` first.*
![Grid](a.png)
*Second use of a.png, same paragraph.*
"""


def test_figures_embedded_with_captions(tmp_path):
    data = {name: _png(tmp_path / name) for name in ("a.png", "b.png", "c.png")}
    (tmp_path / "report.md").write_text(REPORT)
    out = write_html_report(tmp_path / "report.md")
    assert out == tmp_path / HTML_NAME and out.is_file()
    page = out.read_text()
    p = _parse(page)

    # Every image is a data: URI holding exactly the bytes of its PNG file.
    imgs = p.all("img")
    assert [i["alt"] for i in imgs] == ["Force overlay", "Residuals", "Staircase", "Grid"]
    for img, name in zip(imgs, ["a.png", "b.png", "c.png", "a.png"], strict=True):
        head, b64 = img["src"].split(",", 1)
        assert head == "data:image/png;base64"
        assert base64.b64decode(b64) == data[name]
    # Nothing to fetch: no http(s) and no reference to the PNG files.
    assert not re.search(r"https?:", page)
    assert not re.search(r'(src|href)="(?!data:)', page)

    # One <figure> per image; a caption only where the Markdown has one.
    assert len(p.all("figure")) == 4
    assert p.text["figcaption"] == [
        "Measured and modelled force [N] against time [s], run-a.",
        "Error over the noise [1] per model, nominal first.",
        "Second use of a.png, same paragraph.",
    ]
    fig_blocks = re.findall(r"<figure>(.*?)</figure>", page, flags=re.S)
    assert "<figcaption>" not in fig_blocks[1]  # Residuals: no caption line
    assert "<code>nominal</code>" in fig_blocks[2]  # inline Markdown kept in the caption
    assert "<em>" not in "".join(fig_blocks)  # the caption line became the caption


def test_tables_code_title_and_style(tmp_path):
    _png(tmp_path / "a.png")
    page = markdown_to_html(REPORT, tmp_path)
    p = _parse(page)
    assert p.text["title"] == ["Model against measured runs"]
    # The table, whole, inside its own horizontal scroll box.
    assert len(p.all("table")) == 1
    box = re.search(r'<div class="table-scroll">\s*<table>(.*?)</table>\s*</div>', page, re.S)
    assert box and box.group(1).count("<tr>") == 3
    assert "<th>RMS error</th>" in box.group(1) and "<td>2.041 N</td>" in box.group(1)
    # Fenced code kept verbatim, monospace, scrolling.
    assert "nominal-run1     none     2.01/2.04" in page
    css = re.search(r"<style>(.*)</style>", page, re.S).group(1)
    assert "max-width: 60rem" in css
    assert re.search(r"\.table-scroll \{ overflow-x: auto", css)
    assert re.search(r"pre \{ overflow-x: auto", css)
    assert re.search(r"img \{ max-width: 100%", css)
    assert "monospace" in css
    # No script, and a policy that forbids loading anything but data: images.
    assert not p.all("script")
    csp = [m for m in p.all("meta") if m.get("http-equiv") == "Content-Security-Policy"]
    assert csp and csp[0]["content"].startswith("default-src 'none'; img-src data:")


def test_missing_and_remote_figures_become_text(tmp_path):
    md = "# R\n\n![Gone](gone.png)\n*Caption of a lost figure.*\n\n![Web](https://example.org/x.png)\n"
    page = markdown_to_html(md, tmp_path)
    p = _parse(page)
    assert not p.all("img")
    assert "figure not found: Gone (gone.png)" in page
    assert "remote image not loaded: Web" in page
    assert not re.search(r"https?:", page)
    assert p.text["figcaption"] == ["Caption of a lost figure."]


def test_raw_html_is_text(tmp_path):
    page = markdown_to_html('# R\n\nrun <script>alert(1)</script> <img src="x.png">\n', tmp_path)
    assert not _parse(page).all("script") and not _parse(page).all("img")
    assert "&lt;script&gt;" in page


def test_same_text_as_the_markdown(tmp_path):
    """Every word of the Markdown outside its image links is in the page's text
    (the two never disagree)."""
    _png(tmp_path / "a.png")
    page = markdown_to_html(REPORT, tmp_path)
    text = re.sub(r"<[^>]+>", " ", re.sub(r"<style>.*</style>", "", page, flags=re.S))
    words = set(re.findall(r"[A-Za-z_][A-Za-z_0-9.-]{3,}", text))
    for word in re.findall(
        r"[A-Za-z_][A-Za-z_0-9.-]{3,}", re.sub(r"!\[[^\]]*\]\([^)]*\)", "", REPORT)
    ):
        assert word in words, word


@pytest.mark.parametrize("source", ["report.md", "summary.md"])
def test_written_beside_the_markdown(tmp_path, source):
    _png(tmp_path / "a.png")
    md = tmp_path / source
    md.write_text("# Title\n\n![A](a.png)\n*Caption [1].*\n")
    md.chmod(0o644)
    out = write_html_report(md)
    assert out.parent == tmp_path and out.name == "report.html"
    assert out.stat().st_mode & 0o777 == 0o644
    assert f"This page is {source}" in out.read_text()
