"""Example data shipped with swarmtag.

``example_trial.csv`` is a physical-style trial log as a person types it into
a spreadsheet: two conditions (``proximity`` and ``urgency:alpha=3.0``),
twelve runs each, seven carriers per run, times in seconds (``time_unit`` s),
three carriers never delivered, and a free-text ``notes`` column that readers
ignore. ``example_trial_path()`` gives its path, ``example_trial_text()`` its
text, ``example_trial()`` the ``importlib.resources`` resource::

    swarmtag metrics "$(python -c 'import swarmtag.data as d; print(d.example_trial_path())')"
"""

from __future__ import annotations

from swarmtag.data._example import (
    EXAMPLE_TRIAL,
    example_trial,
    example_trial_path,
    example_trial_text,
)

__all__ = ["EXAMPLE_TRIAL", "example_trial", "example_trial_path", "example_trial_text"]
