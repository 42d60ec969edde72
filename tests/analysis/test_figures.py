"""Result figures: written, not blank, and the sweep only where it applies."""

from __future__ import annotations

import pytest
from PIL import Image

from swarmtag.analysis import summarize
from swarmtag.analysis.figures import write_figures
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
