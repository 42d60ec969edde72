"""The metrics stack imports light: no optional or slow packages at import time."""

from __future__ import annotations


def test_core_imports_no_optional_or_slow_packages():
    import subprocess
    import sys

    code = (
        "import sys, swarmtag.io, swarmtag.analysis, swarmtag.cli.metrics;"
        "print(sorted(m for m in ('pyarrow', 'scipy.stats') if m in sys.modules))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"
