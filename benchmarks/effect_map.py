"""Effect map: which sensing and which mechanism let urgency-aware selection pay off.

For every camera range x mechanism (a cell) the script

1. calibrates ``timing.dock`` (1-90 s, log) on the published physical *proximity*
   baseline only (``swarmtag calibrate --baseline lab``; the speed fixed at the robot's
   published limit of 0.5 m/s), and then
2. runs the physical-style comparison on master seeds it did not calibrate on
   (proximity against urgency alpha = 0.7, static urgency, 3 robots / 7 carriers),

and records the differences (PA, P95 and mean latency, throughput; each with its 95 %
bootstrap CI and p-value) and the share of the baseline's selections made among two or
more candidates. The urgency-aware condition is never used to fit anything.

The camera follows the dots rig's measured detection curve (docs/perception.md: 50 % at
1.5 m, every marker within 1.0 m, none beyond 2.0 m) scaled to each range, as a larger
marker would scale it: ``camera.fade = 2/3 * camera.range``. Writes the figure and the
table (``--figure``, ``--table``; docs/reproduction/ by default) and the numbers to
benchmarks/results/ (``_results.py``). Usage:

    .venv/bin/python benchmarks/effect_map.py [--ranges 0.5,1,1.5,2,3,4]
        [--mechanisms camera,memory,turning-walk,narrow-pickup,ble-search,bearing,
                      bearing+look,curved-walk,memory+drift]
        [--runs 64] [--seeds 1,2,3] [--quick] [--figure PNG] [--table MD] [--out JSON]

--quick: ranges 1 and 3, the camera alone and BLE-led search, 16 runs, seed 1 (about a
minute), written to out/effect-map-quick/ unless --figure/--table are given.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
from _results import begin

from swarmtag._plotting import pyplot

ROOT = Path(__file__).resolve().parent.parent
SWARMTAG = [str(Path(sys.executable).parent / "swarmtag")]
"""The CLI of the environment running this script."""

RANGES = (0.5, 1.0, 1.5, 2.0, 3.0, 4.0)
FADE_PER_RANGE = 2.0 / 3.0
"""The dots rig's forward curve: 50 % at 1.5 m, a linear ramp 1.0 m wide (docs/perception.md)."""
MECHANISMS: dict[str, dict[str, object]] = {
    "camera": {},
    "memory": {"camera.memory": 60},
    "turning-walk": {"walk.turn_interval": 2.0, "walk.turn_angle": 60.0},
    "narrow-pickup": {"arena.pickup_width": 1.0},
    "ble-search": {"radio.search": "true"},
    "bearing": {"camera.bearing": "dots"},
    "bearing+look": {"camera.bearing": "dots", "camera.look_around": 2.0},
    "curved-walk": {"walk.curve": 90.0},
    "memory+drift": {"camera.memory": 60, "camera.drift": 0.1},
}
"""Each mechanism's settings on top of the common ones (docs/reproduction.md says what each is)."""
COMMON: dict[str, object] = {
    "perception": "split",
    "camera.occlusion": "carriers",
    "radio.range": 10,
    "radio.interval": 0.25,
    "motion.speed": 0.5,
    "motion.avoid_taken_faces": "true",
    "time_unit": "s",
    "tick": 0.1,
    "timing.pursuit_timeout": 120,
}
"""Every cell: the lab's set-up in seconds, at the robot's published speed limit."""
FREE = "timing.dock=1:90:log"
ALPHA = "urgency:alpha=0.7"
METRICS = ("pa", "p95_latency", "mean_latency", "throughput")


def settings(camera: float, mechanism: str) -> dict[str, object]:
    """The ``--set`` values of one cell."""
    values = dict(COMMON)
    values["camera.range"] = camera
    values["camera.fade"] = round(FADE_PER_RANGE * camera, 6)
    values.update(MECHANISMS[mechanism])
    return values


def set_flags(values: dict[str, object]) -> list[str]:
    """``--set KEY=VALUE`` flags."""
    flags: list[str] = []
    for key, value in values.items():
        flags += ["--set", f"{key}={value}"]
    return flags


def run(command: list[str]) -> str:
    """Run a swarmtag command; its standard output (a failure stops the study)."""
    done = subprocess.run(command, capture_output=True, text=True, check=False, cwd=ROOT)
    if done.returncode != 0:
        raise SystemExit(f"failed ({done.returncode}): {' '.join(command)}\n{done.stderr}")
    return done.stdout


def calibrate(values: dict[str, object], folder: Path) -> tuple[Path, dict[str, Any]]:
    """Fit the dock time on the physical proximity baseline; the profile and its record."""
    profile = folder / "profile.toml"
    command = [*SWARMTAG, "calibrate", "--baseline", "lab", "--profile", "base"]
    command += ["--out", str(profile), "--free", FREE, "--no-progress", *set_flags(values)]
    run(command)
    record = tomllib.loads(profile.read_text())["profile"]["calibration"]
    return profile, record


def compare(profile: Path, seed: int, runs: int) -> dict[str, Any]:
    """The physical-style comparison on ``seed``: ``swarmtag simulate --json``."""
    command = [*SWARMTAG, "simulate", "--profile", str(profile), "--urgency-model", "static"]
    command += ["--ticks", "6000", "--runs", str(runs), "--seed", str(seed), "--json"]
    command += ["--condition", "proximity", "--condition", ALPHA]
    result: dict[str, Any] = json.loads(run(command))
    return result


def cell_row(report: dict[str, Any]) -> dict[str, Any]:
    """One seed's differences (absolute and relative to the baseline) and choice shares."""
    base = next(c for c in report["conditions"] if c["condition"] == "proximity")
    row: dict[str, Any] = {}
    for item in report["comparisons"]:
        metric = item["metric"]
        if metric not in METRICS:
            continue
        reference = base[metric]["value"]
        row[f"d_{metric}"] = item["diff"]
        row[f"d_{metric}_ci"] = item["ci"]
        row[f"p_{metric}"] = item["p_bootstrap"]
        row[f"rel_{metric}"] = item["diff"] / reference if reference else None
    row["baseline_pa"] = base["pa"]["value"]
    choices = next(c for c in report["choices"] if c["condition"] == "proximity")
    row["share_2plus"] = choices["share_2_candidates"] + choices["share_3plus_candidates"]
    return row


def summarise(seeds: list[dict[str, Any]]) -> dict[str, Any]:
    """Over the validation seeds: mean effects, and in how many seeds each is significant."""
    summary: dict[str, Any] = {}
    for metric in METRICS:
        summary[f"d_{metric}"] = float(np.mean([s[f"d_{metric}"] for s in seeds]))
        summary[f"rel_{metric}"] = float(np.mean([s[f"rel_{metric}"] for s in seeds]))
        summary[f"significant_{metric}"] = sum(s[f"p_{metric}"] < 0.05 for s in seeds)
    summary["share_2plus"] = float(np.mean([s["share_2plus"] for s in seeds]))
    summary["baseline_pa"] = float(np.mean([s["baseline_pa"] for s in seeds]))
    return summary


def figure(
    rows: list[dict[str, Any]], ranges: list[float], mechanisms: list[str], path: Path
) -> None:
    """Two heat maps over range x mechanism: the PA gain and the throughput change."""
    plt = pyplot()
    grid = {(r["mechanism"], r["camera"]): r for r in rows}
    panels = (
        ("d_pa", "significant_pa", "PA gain at alpha 0.7 (published +0.23)", "RdBu", 0.4),
        (
            "rel_throughput",
            "significant_throughput",
            "throughput change (published -1.2 %)",
            "RdBu",
            0.4,
        ),
    )
    fig, axes = plt.subplots(
        1, 2, figsize=(12, 0.9 * len(mechanisms) + 2.2), constrained_layout=True
    )
    for ax, (key, significant, title, cmap, limit) in zip(axes, panels, strict=True):
        values = np.array([[grid[(m, c)][key] for c in ranges] for m in mechanisms], dtype=float)
        image = ax.imshow(values, cmap=cmap, vmin=-limit, vmax=limit, aspect="auto")
        for i, mechanism in enumerate(mechanisms):
            for j, camera in enumerate(ranges):
                cell = grid[(mechanism, camera)]
                text = f"{values[i, j]:+.2f}" if key == "d_pa" else f"{100 * values[i, j]:+.0f} %"
                text += f"\n{cell[significant]}/{cell['seeds']} sig."
                ax.text(j, i, text, ha="center", va="center", fontsize=8)
        ax.set_xticks(range(len(ranges)), [f"{c:g} m" for c in ranges])
        ax.set_yticks(range(len(mechanisms)), mechanisms)
        ax.set_xlabel("camera range (50 % detection distance)")
        ax.set_title(title)
        fig.colorbar(image, ax=ax, shrink=0.8)
    fig.suptitle(
        "Physical-style study, dock fitted on the proximity baseline only; validation seeds "
        "not used to fit (sig.: seeds with bootstrap p < 0.05)",
        fontsize=9,
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(rows: list[dict[str, Any]]) -> str:
    """The map as a markdown table, one row per cell."""
    header = (
        "| mechanism | camera | dock (s) | fit | 2+ candidates | ΔPA (sig.) | ΔP95 | Δmean "
        "| Δthroughput (sig.) |"
    )
    lines = [header, "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    lines.extend(
        f"| {r['mechanism']} | {r['camera']:g} m | {r['dock']:.1f} | {r['objective']:.2f} | "
        f"{100 * r['share_2plus']:.0f} % | {r['d_pa']:+.3f} ({r['significant_pa']}/{r['seeds']})"
        f" | {100 * r['rel_p95_latency']:+.1f} % | {100 * r['rel_mean_latency']:+.1f} % | "
        f"{100 * r['rel_throughput']:+.1f} % ({r['significant_throughput']}/{r['seeds']}) |"
        for r in rows
    )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ranges", default=",".join(f"{r:g}" for r in RANGES))
    parser.add_argument("--mechanisms", default=",".join(MECHANISMS))
    parser.add_argument("--runs", type=int, default=64)
    parser.add_argument("--seeds", default="1,2,3")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--figure", type=Path)
    parser.add_argument("--table", type=Path)
    args, record = begin(parser, __file__)
    if args.quick:
        args.ranges, args.mechanisms, args.runs, args.seeds = "1,3", "camera,ble-search", 16, "1"
    folder = ROOT / ("out/effect-map-quick" if args.quick else "docs/reproduction")
    figure_path = args.figure or folder / "effect-map.png"
    table_path = args.table or folder / "effect-map.md"
    ranges = [float(r) for r in args.ranges.split(",")]
    mechanisms = args.mechanisms.split(",")
    unknown = sorted(set(mechanisms) - set(MECHANISMS))
    if unknown:
        raise SystemExit(f"--mechanisms: unknown {unknown}; choose from {list(MECHANISMS)}")
    seeds = [int(s) for s in args.seeds.split(",")]
    started = time.perf_counter()
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as scratch:
        for mechanism in mechanisms:
            for camera in ranges:
                cell_started = time.perf_counter()
                values = settings(camera, mechanism)
                cell_folder = Path(scratch) / f"{mechanism}-{camera:g}"
                cell_folder.mkdir()
                profile, calibration = calibrate(values, cell_folder)
                per_seed = [cell_row(compare(profile, seed, args.runs)) for seed in seeds]
                row = {
                    "mechanism": mechanism,
                    "camera": camera,
                    "dock": calibration["fitted"]["timing.dock"],
                    "objective": calibration["objective"],
                    "seeds": len(seeds),
                    **summarise(per_seed),
                    "per_seed": per_seed,
                    "settings": values,
                    "seconds": time.perf_counter() - cell_started,
                }
                rows.append(row)
                record.row(**row)
                print(
                    f"{mechanism:>13} {camera:4g} m: dock {row['dock']:6.1f} s, fit "
                    f"{row['objective']:.2f}, 2+ {100 * row['share_2plus']:3.0f} %, "
                    f"dPA {row['d_pa']:+.3f} ({row['significant_pa']}/{len(seeds)}), "
                    f"dThroughput {100 * row['rel_throughput']:+.1f} % "
                    f"({row['seconds']:.0f} s)",
                    flush=True,
                )
    figure(rows, ranges, mechanisms, figure_path)
    table_path.parent.mkdir(parents=True, exist_ok=True)
    table_path.write_text(table(rows))
    record.summary["wall_seconds"] = time.perf_counter() - started
    record.summary["runs_per_condition"] = args.runs
    record.summary["validation_seeds"] = seeds
    record.save()
    print(f"figure: {figure_path}\ntable: {table_path}")


if __name__ == "__main__":
    main()
