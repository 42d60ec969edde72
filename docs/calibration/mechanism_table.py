"""Print the mechanism table of docs/calibration.md from the outputs of mechanisms.sh.

Run: ``.venv/bin/python docs/calibration/mechanism_table.py [OUT]`` (default
``out/mechanisms``). For each fitted mechanism: the fitted tick and the
objective over all four baseline set-ups (from its profile's calibration
record), the 3/7 proximity baseline and its choice statistics, then the
treatment directions (differences vs proximity, bootstrap p-values).
"""

from __future__ import annotations

import json
import sys
import tomllib
from pathlib import Path


def _condition(data: dict, name: str) -> dict:
    return next(c for c in data["conditions"] if c["condition"] == name)


def _diff(data: dict, condition: str, metric: str) -> str:
    row = next(
        c for c in data["comparisons"] if c["condition"] == condition and c["metric"] == metric
    )
    digits = 3 if metric == "pa" else 0
    p = row["p_bootstrap"]
    shown = "< 0.001" if p == 0 else f"{p:.2g}"  # 2000 resamples: none crossed zero
    return f"{row['diff']:+.{digits}f} (p {shown})"


def main() -> None:
    """One Markdown row per mechanism, in the order mechanisms.sh fits them."""
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/mechanisms")
    print(
        "| mechanism | tick (s) | objective | P95 | mean | throughput | undelivered "
        "| selections with 2+ candidates | double pursuits / run | timeouts / run "
        "| ΔPA α=0.7 | ΔPA α=9 | ΔP95 α=9 | Δmean α=9 |"
    )
    print("|---" * 14 + "|")
    for profile in sorted(out.glob("*.toml"), key=lambda p: p.stat().st_mtime):
        name = profile.stem
        record = tomllib.loads(profile.read_text())
        calibration = record["profile"]["calibration"]
        data = json.loads((out / f"{name}-treatments.json").read_text())
        base = _condition(data, "proximity")
        choices = next(c for c in data["choices"] if c["condition"] == "proximity")
        multi = choices["share_2_candidates"] + choices["share_3plus_candidates"]
        print(
            f"| {name} | {record['tick']:.4g} | {calibration['objective']:.1f} "
            f"| {base['p95_latency']['value']:.0f} | {base['mean_latency']['value']:.0f} "
            f"| {base['throughput']['value']:.3f} | {base['undelivered']} "
            f"| {multi:.1%} | {choices['double_pursuits_per_run']['value']:.2f} "
            f"| {choices['timeouts_per_run']['value']:.2f} "
            f"| {_diff(data, 'urgency:alpha=0.7', 'pa')} | {_diff(data, 'urgency:alpha=9.0', 'pa')} "
            f"| {_diff(data, 'urgency:alpha=9.0', 'p95_latency')} "
            f"| {_diff(data, 'urgency:alpha=9.0', 'mean_latency')} |"
        )


if __name__ == "__main__":
    main()
