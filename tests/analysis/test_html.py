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
