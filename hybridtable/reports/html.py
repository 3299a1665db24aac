"""A report's Markdown as one self-contained HTML page (``report.html``).

:func:`write_html_report` reads a report's Markdown (``report.md``) and writes
``report.html`` beside it: the same text rendered by Python-Markdown (with the
``tables`` and ``fenced_code`` extensions), so the two never disagree, with

- every figure embedded as a ``data:`` URI (base64), so the page opens alone,
  copied or mailed without its folder; a figure whose file is missing (or
  that points to the network) becomes a line of text saying so;
- a figure written as ``![Short title](file.png)`` with an italic caption line
  ``*...*`` on the next line rendered as ``<figure>`` with ``<figcaption>``;
- its style inline (readable width of about 60 rem, wide tables and code
  blocks scrolling in their own box, figures no wider than the page,
  monospace code), no script, and a content security policy that lets the
  page load nothing from anywhere (``default-src 'none'``);
- raw HTML in the Markdown shown as text, not interpreted (a run id is
  written into the report as the run file gives it).

It refuses nothing: the command that writes the report has already applied
its overwrite policy to the report's folder.
"""

from __future__ import annotations

import base64
import html
import mimetypes
import xml.etree.ElementTree as ET
from pathlib import Path
from urllib.parse import unquote, urlsplit

import markdown
from markdown.extensions import Extension
from markdown.treeprocessors import Treeprocessor

from hybridtable._files import write_text_atomic

__all__ = ["HTML_NAME", "STYLE", "markdown_to_html", "write_html_report"]

#: Name of the page written beside the Markdown report.
HTML_NAME = "report.html"

#: The page's inline style sheet.
STYLE = """
:root { color-scheme: light; }
body { margin: 0; background: #fff; color: #1b1b1b;
  font-family: system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif;
  font-size: 16px; line-height: 1.5; overflow-wrap: break-word; }
main { box-sizing: border-box; max-width: 60rem; margin: 0 auto; padding: 1rem 1.25rem 3rem; }
h1 { font-size: 1.7rem; line-height: 1.25; margin: 0.5rem 0 1rem; }
h2 { font-size: 1.3rem; margin: 2rem 0 0.75rem; padding-bottom: 0.2rem;
  border-bottom: 1px solid #ddd; }
h3 { font-size: 1.1rem; margin: 1.5rem 0 0.5rem; }
code, pre, kbd, samp { font-family: ui-monospace, "DejaVu Sans Mono", Menlo, Consolas,
  "Liberation Mono", monospace; font-size: 0.85em; }
p code, li code, td code, figcaption code { overflow-wrap: anywhere; background: #f3f4f6;
  padding: 0 0.2em; border-radius: 3px; }
pre { overflow-x: auto; background: #f6f8fa; border: 1px solid #e3e6ea; border-radius: 4px;
  padding: 0.75rem; line-height: 1.35; }
pre code { font-size: 0.8rem; background: none; padding: 0; }
.table-scroll { overflow-x: auto; margin: 1rem 0; }
table { border-collapse: collapse; font-size: 0.9rem; }
th, td { border: 1px solid #d0d4d9; padding: 0.25rem 0.55rem; text-align: left;
  vertical-align: top; }
th { background: #f3f4f6; }
tbody tr:nth-child(even) { background: #fafbfc; }
img { max-width: 100%; height: auto; }
figure { margin: 1.5rem 0; }
figure img { display: block; border: 1px solid #e3e6ea; }
figcaption { margin-top: 0.4rem; font-size: 0.9rem; color: #444; }
.missing { color: #8a1c1c; font-style: italic; }
footer { margin-top: 3rem; font-size: 0.8rem; color: #666; }
"""

# Nothing may be loaded from anywhere: images are data: URIs, the style is
# inline and there is no script.
_CSP = "default-src 'none'; img-src data:; style-src 'unsafe-inline'"


def _data_uri(src: str, folder: Path) -> str | None:
    """``src`` (a path relative to ``folder``) as a base64 ``data:`` URI, or
    ``None`` when it is remote, not an image or not a file."""
    if src.startswith("data:"):
        return src
    parts = urlsplit(src)
    if parts.scheme or parts.netloc:  # http(s), file, ...: never fetched
        return None
    path = folder / unquote(parts.path)
    mime = mimetypes.guess_type(path.name)[0]
    if mime is None or not mime.startswith("image/") or not path.is_file():
        return None
    return f"data:{mime};base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def _blank(text: str | None) -> bool:
    return text is None or not text.strip()


class _ReportTree(Treeprocessor):
    """Figures with captions, embedded images, tables in scroll boxes."""

    def __init__(self, md: markdown.Markdown, folder: Path) -> None:
        super().__init__(md)
        self.folder = folder

    def run(self, root: ET.Element) -> None:
        self._figures(root)
        for parent in list(root.iter()):
            for i, child in enumerate(list(parent)):
                if child.tag == "table":
                    box = ET.Element("div", {"class": "table-scroll"})
                    box.tail, child.tail = child.tail, None
                    parent.remove(child)
                    box.append(child)
                    parent.insert(i, box)
        for parent in list(root.iter()):
            for i, child in enumerate(list(parent)):
                if child.tag == "img":
                    self._embed(parent, i, child)

    def _figures(self, root: ET.Element) -> None:
        """A paragraph made only of images, each optionally followed by an
        italic line, becomes one ``<figure>`` per image."""
        for i, p in reversed(list(enumerate(root))):
            kids = list(p)
            if p.tag != "p" or not kids or kids[0].tag != "img" or not _blank(p.text):
                continue
            if any(k.tag not in ("img", "em") or not _blank(k.tail) for k in kids):
                continue
            if any(a.tag == "em" and kids[j - 1].tag != "img" for j, a in enumerate(kids)):
                continue
            figures = []
            for k in kids:
                if k.tag == "img":
                    fig = ET.Element("figure")
                    k.tail = None
                    fig.append(k)
                    figures.append(fig)
                else:
                    cap = ET.SubElement(figures[-1], "figcaption")
                    cap.text = k.text
                    cap.extend(list(k))
            root.remove(p)
            for j, fig in enumerate(figures):
                fig.tail = "\n"
                root.insert(i + j, fig)

    def _embed(self, parent: ET.Element, index: int, img: ET.Element) -> None:
        src = img.get("src", "")
        uri = _data_uri(src, self.folder)
        if uri is not None:
            img.set("src", uri)
            return
        note = ET.Element("span", {"class": "missing"})
        alt = img.get("alt") or "figure"
        parts = urlsplit(src)
        remote = bool(parts.scheme or parts.netloc)
        note.text = (
            f"[remote image not loaded: {alt}]" if remote else f"[figure not found: {alt} ({src})]"
        )
        note.tail = img.tail
        parent.remove(img)
        parent.insert(index, note)


class _ReportExtension(Extension):
    def __init__(self, folder: Path) -> None:
        super().__init__()
        self.folder = folder

    def extendMarkdown(self, md: markdown.Markdown) -> None:  # noqa: N802 (the API's name)
        # Raw HTML is shown as text: nothing in a run file becomes markup.
        md.preprocessors.deregister("html_block")
        md.inlinePatterns.deregister("html")
        md.treeprocessors.register(_ReportTree(md, self.folder), "hybridtable_report", 15)


def _title(text: str, default: str) -> str:
    """The first Markdown heading's text (ATX ``#``), outside code blocks."""
    fenced = False
    for line in text.splitlines():
        s = line.strip()
        if s.startswith(("```", "~~~")):
            fenced = not fenced
        elif not fenced and s.startswith("#"):
            title = s.lstrip("#").strip().rstrip("#").strip()
            if title:
                return title
    return default


def markdown_to_html(text: str, folder: str | Path, source_name: str = "report.md") -> str:
    """The whole HTML page of a Markdown report.

    Parameters
    ----------
    text
        The report's Markdown.
    folder
        Folder the figures' relative paths start from (the report's own).
    source_name
        File name of the Markdown, named in the page's footer.

    Returns
    -------
    str
        A UTF-8 HTML5 document that loads nothing from outside itself.
    """
    body = markdown.markdown(
        text,
        extensions=["tables", "fenced_code", _ReportExtension(Path(folder))],
        output_format="html",
    )
    title = html.escape(_title(text, Path(source_name).stem))
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f'<meta http-equiv="Content-Security-Policy" content="{_CSP}">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<main>\n"
        f"{body}\n"
        f"<footer>This page is {html.escape(source_name)} with its figures embedded.</footer>\n"
        "</main>\n</body>\n</html>\n"
    )


def write_html_report(markdown_path: str | Path, html_name: str = HTML_NAME) -> Path:
    """Write ``html_name`` beside the Markdown report ``markdown_path``.

    Parameters
    ----------
    markdown_path
        The report's Markdown file (``report.md``); its figures are read from
        its folder.
    html_name
        File name of the page, in the same folder (default ``report.html``).

    Returns
    -------
    Path
        The page written (atomically: a reader never sees half of it), with
        the Markdown's permissions.
    """
    md_path = Path(markdown_path)
    out = md_path.parent / html_name
    page = markdown_to_html(md_path.read_text(encoding="utf-8"), md_path.parent, md_path.name)
    write_text_atomic(out, page)
    out.chmod(md_path.stat().st_mode & 0o777)  # readable like report.md, not only by its owner
    return out
