"""The self-contained HTML report: escaping, embedded figures, tables."""

from __future__ import annotations

import base64
import re

from swarmtag.analysis import summarize
from swarmtag.analysis.html import Section, render_html, write_html
from swarmtag.analysis.tables import html_tables, scalability_html
from swarmtag.data import example_trial
from swarmtag.io import parse_carrier_csv

PNG = base64.b64decode(
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="
)


def test_text_is_escaped_and_figures_embedded(tmp_path):
    figure = tmp_path / "pa_curves.png"
    figure.write_bytes(PNG)
    doc = render_html(
        "Report <b>",
        [Section("A & B", paragraphs=["x < y"], figures=[figure], facts={"seed": "<0>"})],
        facts={"swarmtag": "0.1"},
    )
    assert "<title>Report &lt;b&gt;</title>" in doc
    assert "<h2>A &amp; B</h2>" in doc
    assert "<p>x &lt; y</p>" in doc
    assert "<dd>&lt;0&gt;</dd>" in doc
    embedded = re.search(r'src="data:image/png;base64,([^"]+)"', doc)
    assert embedded is not None
    assert base64.b64decode(embedded.group(1)) == PNG
    assert "<figcaption>pa curves</figcaption>" in doc


def test_tables_as_html_match_the_report(tmp_path):
    report = summarize(parse_carrier_csv(example_trial().read_text()), n_resamples=200)
    tables = html_tables(report)
    assert tables.count("<table>") == 2
    assert "<th>urgency:alpha=3.0</th>" in tables
    assert "<td>PA (5-50 %)</td>" in tables
    scal = scalability_html({"3/7": report}, condition="urgency:alpha=3.0")
    assert scal.count("<tr>") == 1 + 6  # header, six metrics
    # Undelivered differs (2 vs 1): the note follows the table, the P95 row is flagged.
    assert "<td>P95 latency (s) \N{DAGGER}</td>" in scal
    assert scal.endswith("compare the censored rows.</p>")
    path = tmp_path / "r.html"
    write_html(path, "t", [Section("s", tables_html=[tables, scal])], facts={})
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>")
    assert text.count("<table>") == 3


def test_a_figure_of_panels_side_by_side_gets_the_page_width(tmp_path):
    from PIL import Image

    wide, square = tmp_path / "pareto.png", tmp_path / "curves.png"
    Image.new("RGB", (900, 300), "white").save(wide)
    Image.new("RGB", (400, 300), "white").save(square)
    doc = render_html("r", [Section("s", figures=[wide, square])], facts={})
    figures = re.findall(r"<figure[^>]*>", doc)
    assert figures == ['<figure class="wide">', "<figure>"]


def test_a_folded_section_holds_its_parts_one_level_down():
    inner = Section("swarm 5x10", tables_html=["<table><tr><td>1</td></tr></table>"])
    doc = render_html(
        "r",
        [Section("scalability", summary="3 runs per condition", facts={"a": "b"}, parts=[inner])],
        facts={},
    )
    folded = doc[doc.index("<details>") : doc.index("</details>")]
    assert folded.startswith(
        '<details>\n<summary><h2>scalability</h2><span class="runs">3 runs per condition</span>'
        "</summary>\n<dl>"
    )
    assert "<h3>swarm 5x10</h3>" in folded
    # every table scrolls in its own box, so a wide one does not widen the page
    assert '<div class="scroll"><table><tr><td>1</td></tr></table></div>' in folded
    unfolded = render_html("r", [Section("plain")], facts={})
    assert "<details>" not in unfolded
    assert "<h2>plain</h2>" in unfolded


def test_the_page_reads_at_phone_width_and_a_banner_leads():
    doc = render_html("r", [Section("s")], facts={"x": "y"}, banner="Quick run: run `a & b`.")
    assert '<meta name="viewport" content="width=device-width, initial-scale=1">' in doc
    assert "@media (max-width: 40em)" in doc
    assert "max-width: 72em" in doc
    banner = '<p class="banner">Quick run: run <code>a &amp; b</code>.</p>'
    assert doc.index("<h1>r</h1>") < doc.index(banner) < doc.index("<dl>")
    assert 'class="banner"' not in render_html("r", [Section("s")], facts={})


def test_a_figure_shows_the_caption_its_png_carries(tmp_path):
    from PIL import Image
    from PIL.PngImagePlugin import PngInfo

    from swarmtag.analysis.html import CAPTION_KEY, png_text

    latin, greek = PngInfo(), PngInfo()
    latin.add_text(CAPTION_KEY, "PA against p < 50.")
    greek.add_text(CAPTION_KEY, "PA at \N{GREEK SMALL LETTER ALPHA} 0.7.")  # iTXt: not latin-1
    plain = tmp_path / "pa_curves.png"
    Image.new("RGB", (40, 30), "white").save(plain)
    for name, info in (("latin.png", latin), ("greek.png", greek)):
        Image.new("RGB", (40, 30), "white").save(tmp_path / name, pnginfo=info)
    assert png_text((tmp_path / "greek.png").read_bytes(), CAPTION_KEY) == (
        "PA at \N{GREEK SMALL LETTER ALPHA} 0.7."
    )
    assert png_text(plain.read_bytes(), CAPTION_KEY) is None
    figures = [tmp_path / "latin.png", tmp_path / "greek.png", plain]
    doc = render_html("r", [Section("s", figures=figures)], facts={})
    captions = re.findall(r"<figcaption>([^<]*)</figcaption>", doc)
    assert captions == ["PA against p &lt; 50.", "PA at \N{GREEK SMALL LETTER ALPHA} 0.7.",
                        "pa curves"]  # fmt: skip
    assert re.findall(r'alt="([^"]*)"', doc) == ["latin", "greek", "pa curves"]
