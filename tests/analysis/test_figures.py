"""Result figures: written, not blank, and the sweep only where it applies."""

from __future__ import annotations

import pytest
from PIL import Image

from swarmtag.analysis import summarize
from swarmtag.analysis.figures import condition_colours, write_figures
from swarmtag.analysis.html import CAPTION_KEY, png_text
from swarmtag.data import example_trial
from swarmtag.io import CarrierLog, parse_carrier_csv


def _png_ok(path):
    with Image.open(path) as image:
        assert image.format == "PNG"
        assert len(image.convert("RGB").getcolors(maxcolors=1_000_000) or []) > 50


def test_trial_log_gets_curves_and_urgency_but_no_sweep(tmp_path):
    log = parse_carrier_csv(example_trial().read_text())
    report = summarize(log, n_resamples=300)
    written = write_figures(report, log, tmp_path)
    assert [p.name for p in written] == [
        "pa_curves.png",
        "latency_curves.png",
        "urgency_latency.png",
    ]
    for path in written:
        _png_ok(path)


def test_one_policy_sweep_gets_the_sweep_figure(tmp_path):
    log = parse_carrier_csv(example_trial().read_text())
    # Rename the two conditions into a two-point urgency sweep.
    renamed = CarrierLog(
        **{**log.columns(), "condition": [
            "urgency:alpha=0.5" if c == "proximity" else "urgency:alpha=3.0" for c in log.condition
        ]},
        time_unit=log.time_unit,
    )  # fmt: skip
    report = summarize(renamed, n_resamples=300)
    written = write_figures(report, renamed, tmp_path)
    assert written[-1].name == "sweep.png"
    _png_ok(written[-1])


def test_missing_extra_message(monkeypatch):
    import builtins

    from swarmtag._plotting import pyplot
    from swarmtag.errors import ConfigError

    real_import = builtins.__import__

    def no_matplotlib(name, *args, **kwargs):
        if name.startswith("matplotlib"):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    with pytest.raises(ConfigError, match=r"swarmtag\[plot\]"):
        pyplot()


SWEEP = [f"weighted:w={w / 10:.1f}" for w in range(11)]


def sweep_log():
    """The example trial's 24 runs dealt out to the eleven weights of the preliminary sweep."""
    log = parse_carrier_csv(example_trial().read_text())
    pairs = sorted({(str(c), int(r)) for c, r in zip(log.condition, log.run, strict=True)})
    index = {pair: i for i, pair in enumerate(pairs)}
    dealt = [index[(str(c), int(r))] for c, r in zip(log.condition, log.run, strict=True)]
    return CarrierLog(
        **{**log.columns(), "condition": [SWEEP[i % 11] for i in dealt],
           "run": [i // 11 for i in dealt]},
        time_unit=log.time_unit,
    )  # fmt: skip


def _rgb(colour):
    return tuple(round(255 * channel) for channel in colour[:3])


def _pixels(path):
    with Image.open(path) as image:
        return {rgb for _, rgb in image.convert("RGB").getcolors(maxcolors=1_000_000)}


def test_a_sweep_of_eleven_weights_gets_eleven_distinct_colours_in_order(tmp_path):
    colours = condition_colours(list(reversed(SWEEP)))  # the order given does not matter
    rgb = [_rgb(colours[name]) for name in SWEEP]
    assert len(set(rgb)) == 11  # w = 0.0 and w = 1.0 no longer share a blue
    # sequential: viridis runs from dark to light along w
    luminance = [0.2126 * r + 0.7152 * g + 0.0722 * b for r, g, b in rgb]
    assert luminance == sorted(luminance)
    assert luminance[-1] - luminance[0] > 100
    log = sweep_log()
    report = summarize(log, baseline="weighted:w=0.0", n_resamples=200)
    written = {path.name: path for path in write_figures(report, log, tmp_path)}
    # every condition's line (and the sweep's points) is drawn in its own colour
    for name in ("pa_curves.png", "latency_curves.png", "urgency_latency.png", "sweep.png"):
        drawn = _pixels(written[name])
        assert [c for c in rgb if c not in drawn] == [], name


def test_other_conditions_get_a_qualitative_palette():
    import matplotlib as mpl

    names = ["proximity", "urgency:alpha=0.7", "urgency:alpha=3.0", "urgency:alpha=9.0"]
    tab10 = mpl.colormaps["tab10"]
    assert [_rgb(c) for c in condition_colours(names).values()] == [
        _rgb(tab10(i)) for i in range(4)
    ]
    many = [f"rule-{i}" for i in range(14)]  # past ten: tab20, still distinct
    assert len({_rgb(c) for c in condition_colours(many).values()}) == 14


def test_legends_sit_outside_the_data_and_every_figure_has_a_caption(tmp_path, monkeypatch):
    from swarmtag.analysis import figures

    saved = figures._save
    checked = []

    def check_then_save(fig, path, caption):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        for ax in fig.axes:
            legends = [a for a in ax.get_children() if type(a).__name__ == "Legend"]
            for legend in legends:
                box, data = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
                assert box.x0 >= data.x1 or box.y1 <= data.y0, path  # right of it, or below
                checked.append(path.name)
        saved(fig, path, caption)

    monkeypatch.setattr(figures, "_save", check_then_save)
    log = sweep_log()
    report = summarize(log, baseline="weighted:w=0.0", n_resamples=200)
    written = write_figures(report, log, tmp_path)
    assert checked == ["pa_curves.png", "latency_curves.png", "urgency_latency.png"]
    captions = [png_text(path.read_bytes(), CAPTION_KEY) for path in written]
    assert all(c is not None and len(c) > 60 and c.endswith(".") for c in captions), captions
    assert len(set(captions)) == len(captions)
    assert "against the policy parameter w" in captions[-1]
    # the figure's whole legend made it into the picture: nothing cut at the right edge
    with Image.open(written[2]) as image:
        width, height = image.size
        right = image.convert("RGB").crop((width - 3, 0, width, height))
        assert {rgb for _, rgb in right.getcolors()} == {(255, 255, 255)}


def test_each_figure_is_drawn_once_and_figure_files_names_them(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from swarmtag.analysis.figures import figure_files

    draws = []
    draw = Figure.draw

    def counted(self, renderer):
        draws.append(self)
        return draw(self, renderer)

    monkeypatch.setattr(Figure, "draw", counted)
    log = sweep_log()
    report = summarize(log, baseline="weighted:w=0.0", n_resamples=50)
    written = write_figures(report, log, tmp_path)
    assert figure_files(report, tmp_path) == written
    assert len(written) == 4
    assert len(draws) == len(set(draws)) == 4  # no second draw to measure the bounds
    for path in written:
        with Image.open(path) as image:
            assert image.mode == "RGB"
            assert image.size == (768, 504)  # 6.4 x 4.2 in at 120 pixels per inch
            break
