"""One self-contained HTML report: sections of text, tables and embedded PNG figures.

Figures are embedded as base64 data URIs, so the report is a single file
that can be mailed or archived; a figure's caption is the ``Description``
text its PNG carries (``swarmtag.analysis.figures`` writes one), else its
file name. Tables come from ``swarmtag.analysis.tables`` (already escaped
HTML) and scroll sideways inside their own box; every other string is
escaped here. A section can be folded (``<details>``) and hold sub-sections;
the page reads at phone width.
"""

from __future__ import annotations

import base64
import html
import os
import re
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final

from swarmtag._atomic import atomic_write_bytes

__all__ = ["CAPTION_KEY", "Section", "png_text", "render_html", "write_html"]

CAPTION_KEY: Final = "Description"
"""The PNG text key whose value is shown under an embedded figure."""

_STYLE: Final = """
body { font: 16px/1.45 system-ui, sans-serif; max-width: 72em; margin: 0 auto;
  padding: 1em 1.2em 3em; color: #222; }
h1 { font-size: 1.6em; margin: 0.4em 0; } h3 { font-size: 1.05em; margin-top: 1.5em; }
h2 { font-size: 1.3em; margin-top: 1.6em; border-bottom: 1px solid #ccc; }
.banner { background: #fff4d6; border-left: 5px solid #d99a00; padding: 0.6em 0.9em; }
.scroll { overflow-x: auto; max-width: 100%; margin: 0.8em 0; }
table { border-collapse: collapse; font-size: 0.85em; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.6em; text-align: right; vertical-align: top; }
th:first-child, td:first-child { text-align: left; }
thead { background: #f3f3f3; } .note { color: #555; font-size: 0.85em; }
table.verdicts td, table.verdicts th { text-align: left; }
table.verdicts td.num { text-align: right; white-space: nowrap; }
table.verdicts td.part { white-space: nowrap; }
table.verdicts td.claim { min-width: 12em; }
.v-reproduced { background: #dff3df; } .v-sign { background: #fde9c8; }
.v-not { background: #f8d8d8; } .v-under { background: #ececec; }
details { border-bottom: 1px solid #ccc; padding: 0.3em 0; }
summary { cursor: pointer; padding: 0.4em 0; }
summary h2 { display: inline; border: 0; margin: 0; font-size: 1.2em; }
summary .runs { color: #555; font-size: 0.9em; margin-left: 0.5em; }
figure { display: inline-block; vertical-align: top; width: min(100%, 34em); margin: 0.5em 0.8em
  0.8em 0; } figure img { width: 100%; height: auto; }
figure.wide { display: block; width: min(100%, 60em); }
figcaption { font-size: 0.85em; color: #444; }
dl { display: grid; grid-template-columns: max-content auto; gap: 0.2em 1em; }
dt { font-weight: bold; } dd { margin: 0; overflow-wrap: anywhere; }
code { background: #f3f3f3; padding: 0 0.2em; }
@media (max-width: 40em) {
  body { font-size: 15px; padding: 0.6em 0.7em 2em; } h1 { font-size: 1.35em; }
  dl { display: block; } dd { margin: 0 0 0.4em 0; } figure { margin: 0.5em 0; }
}
"""
_TABLE: Final = re.compile(r"<table\b.*?</table>", re.DOTALL)


@dataclass(frozen=True, slots=True)
class Section:
    """One study (or part) of the report: a title, paragraphs, HTML tables and figure files."""

    title: str
    paragraphs: Sequence[str] = ()
    tables_html: Sequence[str] = ()
    figures: Sequence[str | os.PathLike[str]] = ()
    facts: Mapping[str, str] = field(default_factory=dict)
    """Parameters and other key facts, shown as a definition list."""
    summary: str = ""
    """When set, the section is folded (closed ``<details>``) with this line after its title."""
    parts: Sequence[Section] = ()
    """Sub-sections, one heading level down, after the section's own content."""


def png_text(raw: bytes, key: str) -> str | None:
    """The value of a PNG's ``tEXt`` or ``iTXt`` chunk named ``key``, if it has one.

    >>> chunk = (4).to_bytes(4, "big") + b"tEXt" + b"k" + bytes(1) + b"v!" + bytes(4)
    >>> png_text(bytes(8) + chunk, "k"), png_text(bytes(8) + chunk, "other")
    ('v!', None)
    """
    position = 8  # after the signature
    while position + 8 <= len(raw):
        length = int.from_bytes(raw[position : position + 4], "big")
        kind = raw[position + 4 : position + 8]
        data = raw[position + 8 : position + 8 + length]
        position += 12 + length  # length, type, data, CRC
        name, _, rest = data.partition(b"\0")
        if name != key.encode("latin-1"):
            continue
        if kind == b"tEXt":
            return rest.decode("latin-1")
        if kind == b"iTXt" and len(rest) >= 2:
            compressed, text = rest[0], rest[2:].split(b"\0", 2)[-1]  # after language, key
            return (zlib.decompress(text) if compressed else text).decode("utf-8")
    return None


def _figure(path: str | os.PathLike[str]) -> str:
    raw = Path(path).read_bytes()
    data = base64.b64encode(raw).decode("ascii")
    name = html.escape(Path(path).stem.replace("_", " "))
    caption = png_text(raw, CAPTION_KEY)
    # A PNG's IHDR holds width and height at bytes 16-23: a figure of panels side by side
    # (wider than twice its height) gets the page's width rather than a thumbnail's.
    wide = int.from_bytes(raw[16:20], "big") > 2 * int.from_bytes(raw[20:24], "big")
    kind = ' class="wide"' if wide else ""
    return (
        f'<figure{kind}><img alt="{name}" src="data:image/png;base64,{data}">'
        f"<figcaption>{name if caption is None else html.escape(caption)}</figcaption></figure>"
    )


def _facts(facts: Mapping[str, str]) -> str:
    items = "".join(
        f"<dt>{html.escape(key)}</dt><dd>{html.escape(value)}</dd>" for key, value in facts.items()
    )
    return f"<dl>{items}</dl>" if items else ""


def _scrolling(tables: str) -> str:
    """Each ``<table>`` in a box of its own that scrolls sideways: the page keeps its width."""
    return _TABLE.sub(lambda found: f'<div class="scroll">{found.group(0)}</div>', tables)


def _inline(text: str) -> str:
    """Escaped text with `backticked` spans as ``<code>``."""
    pieces = html.escape(text).split("`")
    return "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(pieces))


def _section(section: Section, level: int) -> list[str]:
    heading = f"<h{level}>{html.escape(section.title)}</h{level}>"
    body = [_facts(section.facts)]
    body += [f"<p>{html.escape(text)}</p>" for text in section.paragraphs]
    body += [_scrolling(tables) for tables in section.tables_html]
    body += [_figure(path) for path in section.figures]
    for part in section.parts:
        body += _section(part, level + 1)
    if not section.summary:
        return [heading, *body]
    line = f'<span class="runs">{html.escape(section.summary)}</span>'
    return ["<details>", f"<summary>{heading}{line}</summary>", *body, "</details>"]


def render_html(
    title: str, sections: Sequence[Section], *, facts: Mapping[str, str], banner: str = ""
) -> str:
    """The whole report as one HTML document string; ``banner`` (text) is shown under the title.

    >>> doc = render_html("R", [Section("Study <1>", paragraphs=["a & b"])], facts={"seed": "0"})
    >>> "<h2>Study &lt;1&gt;</h2>" in doc and "<p>a &amp; b</p>" in doc
    True
    """
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>",
        f'<p class="banner">{_inline(banner)}</p>' if banner else "",
        _facts(facts),
    ]
    for section in sections:
        parts += _section(section, 2)
    parts.append("</body></html>")
    return "\n".join(part for part in parts if part) + "\n"


def write_html(
    path: str | os.PathLike[str],
    title: str,
    sections: Sequence[Section],
    *,
    facts: Mapping[str, str],
    banner: str = "",
) -> None:
    """Write the report atomically."""
    atomic_write_bytes(
        path, render_html(title, sections, facts=facts, banner=banner).encode("utf-8")
    )
