"""Measure the camera range of a rig on synthetic images (docs/perception.md shows the result).

Writes, into --out (default docs/perception/RIG): range.png (the figure), range.md (the
table), range.json (every number), examples.png (crops of a few of the study's kind of
images) and prints the reliable range next to the simulator's camera ranges; the summary
(reliable ranges, images, errors, wall time) with the machine's facts goes to
benchmarks/results/ (--results FILE.json to choose; _results.py). Usage:

    .venv/bin/python benchmarks/camera_range.py [--rig dots-like] [--samples 40] [--seed 0]
        [--bearings 0,15,30,45] [--quick] [--out DIR] [--results FILE.json]

--quick: 8 samples per point on a coarse grid (a minute), for trying settings out; it
writes into out/camera-range-quick unless --out is given, so the documented files stay.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from _results import begin

from swarmtag.perception import (
    LOOSE_RATE,
    MIN_RATE,
    Conditions,
    Nuisance,
    Placement,
    centring_offset,
    detect_markers,
    fuse,
    load_rig,
    plot_range_study,
    render,
    run_range_study,
)
from swarmtag.sim.config.profiles import PROFILES, load_profile

DISTANCES = tuple(np.round(np.arange(0.5, 4.01, 0.25), 2))
QUICK_DISTANCES = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0)
BEARINGS = (0.0, 15.0, 30.0, 45.0)


def simulator_ranges() -> dict[str, float]:
    """``camera.range`` of every shipped simulator profile."""
    return {name: load_profile(name).scenario().camera.range for name in PROFILES}


def examples(rig, path: Path, seed: int) -> None:
    """A 2 x 2 montage of image crops around the carrier: near, mid, far, and the upward view.

    The upward view is shown whole, scaled to fit its tile; on a rig whose carriers carry
    an underside map, its label says what ``centring_offset`` read from the map.
    """
    import cv2  # noqa: PLC0415 - the vision extra, as the package imports it

    rng = np.random.default_rng(np.random.SeedSequence(seed).spawn(1)[0])
    conditions = Conditions(blur=0.6, noise=3.0, exposure=0.9)
    front = rig.facing(10.0)
    tiles = []
    for distance, turn in ((0.75, 20.0), (1.5, -30.0), (2.5, 10.0)):
        placement = Placement.at(7, distance, 10.0, turn)
        image = render(front, rig.carrier, [placement], conditions, rng=rng)
        found = fuse(detect_markers(image, front, rig.carrier), rig.carrier)
        note = f"{distance} m: " + (
            f"id {found[0].marker}, {found[0].distance:.3f} m" if found else "not detected"
        )
        tiles.append((image, placement, note))
    upward = next(camera for camera in rig.cameras if camera.upward)
    placement = Placement(7, 0.02, -0.01, 15.0)
    image = render(upward, rig.carrier, [placement], conditions, rng=rng)
    note = "upward camera, carrier 2 cm ahead, 1 cm right"
    if rig.carrier.underside_map is not None:
        read = centring_offset(detect_markers(image, upward, rig.carrier))
        note = (  # the truth: (2.0, -1.0) cm, 15 deg
            f"upward: {read.markers} map markers, ({read.offset[0] * 100:.1f}, "
            f"{read.offset[1] * 100:.1f}) cm, {read.yaw:.1f} deg"
            if read is not None
            else "upward: map not read"
        )
    tiles.append((image, None, note))
    crops = []
    for image, placement, note in tiles:
        h, w = image.shape
        cy, cx = h // 2, w // 2
        if placement is not None:  # centre the crop on the carrier's near face
            centre = front.mount.to_camera(np.array([placement.x, placement.y, 0.1]))
            pixel = front.intrinsics.matrix @ centre
            cx = int(np.clip(pixel[0] / pixel[2], 240, w - 240))
        crop = image[max(cy - 135, 0) : cy + 135, cx - 240 : cx + 240].copy()
        if placement is None:  # the upward view is large: show it whole, scaled to fit
            scale = min(480 / w, 270 / h)
            size = (round(w * scale), round(h * scale))
            crop = np.zeros((270, 480), dtype=np.uint8)
            left, top = (480 - size[0]) // 2, (270 - size[1]) // 2
            crop[top : top + size[1], left : left + size[0]] = cv2.resize(
                image, size, interpolation=cv2.INTER_AREA
            )
        cv2.rectangle(crop, (0, 0), (crop.shape[1] - 1, 30), 0, thickness=-1)
        cv2.putText(crop, note, (8, 21), cv2.FONT_HERSHEY_SIMPLEX, 0.55, 255, 1, cv2.LINE_AA)
        crops.append(crop)
    montage = np.vstack([np.hstack(crops[:2]), np.hstack(crops[2:])])
    cv2.imwrite(str(path), montage)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rig", default="dots-like")
    parser.add_argument("--samples", type=int, default=40)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--bearings",
        default=",".join(f"{b:g}" for b in BEARINGS),
        help="comma-separated bearings (deg from the robot's forward axis)",
    )
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path, default=None, help="folder of the figure and table")
    args, record = begin(parser, __file__, flag="--results")
    rig = load_rig(args.rig)
    if args.out is None:
        args.out = Path("out/camera-range-quick" if args.quick else f"docs/perception/{rig.name}")
    args.out.mkdir(parents=True, exist_ok=True)
    distances = QUICK_DISTANCES if args.quick else DISTANCES
    samples = 8 if args.quick else args.samples
    started = time.perf_counter()

    def progress(done: int, total: int) -> None:
        print(f"\r{done}/{total} cells, {time.perf_counter() - started:.0f} s", end="", flush=True)

    study = run_range_study(
        rig,
        distances=distances,
        bearings=tuple(float(b) for b in args.bearings.split(",")),
        samples=samples,
        seed=args.seed,
        nuisance=Nuisance(),
        progress=progress,
    )
    print()
    ranges = simulator_ranges()
    marks = [
        (value, f"simulator camera.range ({', '.join(n for n, v in ranges.items() if v == value)})")
        for value in sorted(set(ranges.values()))
    ]
    plot_range_study(study, args.out / "range.png", marks=marks)
    (args.out / "range.md").write_text(study.table(), encoding="utf-8")
    study.save_json(args.out / "range.json")
    examples(rig, args.out / "examples.png", args.seed)
    print(study.table())
    for rate in (MIN_RATE, LOOSE_RATE):  # the reliable range, then the looser one to compare
        band = study.reliable_range(min_rate=rate)
        images, found, worst = study.inside(min_rate=rate)
        record.row(
            min_rate=rate,
            reliable_range_m=band,
            images_inside=images,
            identified_inside=found,
            largest_distance_error=worst,
        )
        print(
            f"rig {rig.name}, detection >= {rate:.0%} and every distance within 5 %: "
            f"range {band} m; inside it {found}/{images} detected, largest distance error "
            f"{worst * 100:.2f} %"
        )
        if band is not None and found < images:
            rows = (study.distances >= band[0]) & (study.distances <= band[1])
            for i in np.flatnonzero(rows):
                for j, bearing in enumerate(study.bearings):
                    missed = int((~study.detected[i, j]).sum())
                    if missed:
                        print(
                            f"  missed {missed}/{study.samples} at {study.distances[i]:g} m, "
                            f"bearing {bearing:g} deg"
                        )
    print(f"wrong ids: {int(study.wrong.sum())}")
    print("simulator camera.range:", ", ".join(f"{n} {v:g} m" for n, v in ranges.items()))
    print(f"{study.detected.size} images in {time.perf_counter() - started:.0f} s")
    record.summary.update(
        rig=rig.name,
        images=int(study.detected.size),
        wrong_ids=int(study.wrong.sum()),
        simulator_camera_range_m=ranges,
    )
    record.save()


if __name__ == "__main__":
    main()
