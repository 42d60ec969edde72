"""One self-contained HTML report: sections of text, tables and embedded PNG figures.

Figures are embedded as base64 data URIs, so the report is a single file
that can be mailed or archived. Tables come from ``swarmtag.analysis.tables``
(already escaped HTML); every other string is escaped here.
"""

from __future__ import annotations

import base64
import html
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final

from swarmtag._atomic import atomic_write_bytes

__all__ = ["Section", "render_html", "write_html"]

_STYLE: Final = """
body { font-family: system-ui, sans-serif; max-width: 70em; margin: 2em auto; color: #222; }
h1 { font-size: 1.6em; } h2 { font-size: 1.3em; margin-top: 2em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
table { display: block; overflow-x: auto; max-width: 100%; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; }
th:first-child, td:first-child { text-align: left; }
thead { background: #f3f3f3; } .note { color: #555; font-size: 0.85em; }
figure { display: inline-block; margin: 0.5em; } img { max-width: 32em; }
figure.wide { display: block; } figure.wide img { max-width: min(100%, 96em); }
dl { display: grid; grid-template-columns: max-content auto; gap: 0.2em 1em; }
dt { font-weight: bold; }
"""


@dataclass(frozen=True, slots=True)
class Section:
    """One study (or part) of the report: a title, paragraphs, HTML tables and figure files."""

    title: str
    paragraphs: Sequence[str] = ()
    tables_html: Sequence[str] = ()
    figures: Sequence[str | os.PathLike[str]] = ()
    facts: Mapping[str, str] = field(default_factory=dict)
    """Parameters and other key facts, shown as a definition list."""


def _figure(path: str | os.PathLike[str]) -> str:
    raw = Path(path).read_bytes()
    data = base64.b64encode(raw).decode("ascii")
    caption = html.escape(Path(path).stem.replace("_", " "))
    # A PNG's IHDR holds width and height at bytes 16-23: a figure of panels side by side
    # (wider than twice its height) gets the page's width rather than a thumbnail's.
    wide = int.from_bytes(raw[16:20], "big") > 2 * int.from_bytes(raw[20:24], "big")
    kind = ' class="wide"' if wide else ""
    return (
        f'<figure{kind}><img alt="{caption}" src="data:image/png;base64,{data}">'
        f"<figcaption>{caption}</figcaption></figure>"
    )


def _facts(facts: Mapping[str, str]) -> str:
    items = "".join(
        f"<dt>{html.escape(key)}</dt><dd>{html.escape(value)}</dd>" for key, value in facts.items()
    )
    return f"<dl>{items}</dl>" if items else ""


def render_html(title: str, sections: Sequence[Section], *, facts: Mapping[str, str]) -> str:
    """The whole report as one HTML document string.

    >>> doc = render_html("R", [Section("Study <1>", paragraphs=["a & b"])], facts={"seed": "0"})
    >>> "<h2>Study &lt;1&gt;</h2>" in doc and "<p>a &amp; b</p>" in doc
    True
    """
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        _facts(facts),
    ]
    for section in sections:
        parts.append(f"<h2>{html.escape(section.title)}</h2>")
        parts.append(_facts(section.facts))
        parts += [f"<p>{html.escape(text)}</p>" for text in section.paragraphs]
        parts += list(section.tables_html)
        parts += [_figure(path) for path in section.figures]
    parts.append("</body></html>")
    return "\n".join(part for part in parts if part) + "\n"


def write_html(
    path: str | os.PathLike[str],
    title: str,
    sections: Sequence[Section],
    *,
    facts: Mapping[str, str],
) -> None:
    """Write the report atomically."""
    atomic_write_bytes(path, render_html(title, sections, facts=facts).encode("utf-8"))
