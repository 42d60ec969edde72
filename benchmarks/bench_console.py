"""Load on the operator's console: 1,000 tags and 100 robots, 10 updates a second, a real browser.

Run: ``.venv/bin/python benchmarks/bench_console.py [--robots 100] [--tags 1000] [--rate 10]
[--seconds 20] [--out FILE.json]`` (the console and dev extras, and Chromium at
``/usr/bin/chromium`` or ``SWARMTAG_CHROMIUM``).

A child process serves ``swarmtag console --sim``'s app (``console.app.make_app``) over a
live warehouse: ``--robots`` robots on a generated map (``bench_warehouse.generated_map``,
the lab profile, one order every ``--order-interval`` seconds), stepped ahead until
``--tags`` tags are on the floor, then in real time, its event stream sending the whole
state ``--rate`` times a second. Headless Chromium (Playwright) opens the page and, for
``--seconds``, counts what it receives and how long it takes:

- the server's CPU (the child's user + system seconds per wall second: stepping the
  simulation, the snapshots, JSON, HTTP) and whether its clock kept up with the wall;
- the browser's: the events received per second and the time each takes to receive
  (parsing), the page's draws per second (it draws the latest state at its next frame)
  and the time each takes (the floor and the table), the frames' intervals
  (``requestAnimationFrame``), the long tasks (over 50 ms), the CPU of Chromium's
  processes, and the lag of the page's last state behind the server's clock at the end.

The page keeps up (``summary.keeps_up``) if it receives and draws at least 90 % of the
updates and its p95 receiving plus p95 drawing stays under the update interval.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

import psutil
from _results import begin
from bench_warehouse import WORKLOAD, generated_map

CHROMIUM = Path(os.environ.get("SWARMTAG_CHROMIUM", "/usr/bin/chromium"))

PROBE = """
(() => {
  const bench = { events: 0, handling: [], draws: 0, drawing: [], frames: [], long: [],
    lastTime: null };
  window.__bench = bench;
  window.addEventListener("load", () => {  // the page's own drawing, at most once a frame
    const draw = window.drawState;
    window.drawState = () => {
      const start = performance.now();
      draw();
      bench.drawing.push(performance.now() - start);
      bench.draws += 1;
    };
  });
  const Native = window.EventSource;
  window.EventSource = class extends Native {
    addEventListener(type, listener, options) {
      if (type !== "state") return super.addEventListener(type, listener, options);
      return super.addEventListener(type, (event) => {
        const start = performance.now();
        listener(event);
        bench.handling.push(performance.now() - start);
        bench.events += 1;
        const found = /"time":([0-9.]+)/.exec(event.data);
        bench.lastTime = found ? Number(found[1]) : null;
      }, options);
    }
  };
  let then = null;
  const frame = (now) => {
    if (then !== null) bench.frames.push(now - then);
    then = now;
    requestAnimationFrame(frame);
  };
  requestAnimationFrame(frame);
  new PerformanceObserver((list) => {
    for (const entry of list.getEntries()) bench.long.push(entry.duration);
  }).observe({ entryTypes: ["longtask"] });
})();
"""
"""Injected before the page's own script: wraps its ``state`` listener and counts frames."""


def scenario_of(args: argparse.Namespace, folder: Path) -> Any:
    """The lab profile on a generated warehouse map for ``--robots``, orders every interval."""
    from swarmtag.sim import load_profile  # noqa: PLC0415 - the child's import

    path = folder / f"generated-{args.robots}.txt"
    path.write_text(generated_map(args.robots), encoding="utf-8")
    part = {
        "map": os.fspath(path),
        "order_interval": args.order_interval,
        "initial_orders": 8,
        "warmup": 0.0,
    }
    lab = load_profile("lab")
    tick = lab.scenario({}).tick
    # the orders that bring --tags tags, then the measured window and a minute to spare: a
    # run no longer than that keeps the carriers (which the sensing pairs with every robot) few
    ticks = math.ceil(1.1 * args.tags * args.order_interval / tick)
    ticks += math.ceil((args.seconds + 60) / tick)
    return lab.scenario({"robots": args.robots, "ticks": ticks, "warehouse": part, **WORKLOAD})


def serve(args: argparse.Namespace) -> None:
    """The child: build the console, step ahead to ``--tags`` tags, print the URL, serve."""
    import uvicorn  # noqa: PLC0415 - the console extra

    from swarmtag.console.app import make_app  # noqa: PLC0415
    from swarmtag.console.server import ConsoleSettings, bind, build_core  # noqa: PLC0415
    from swarmtag.policy import parse_policy  # noqa: PLC0415

    folder = Path(args.folder)
    core = build_core(
        ConsoleSettings(
            scenario=scenario_of(args, folder),
            policy=parse_policy("urgency:alpha=0.7"),
            audit_log=folder / "audit.jsonl",
            counter_file=folder / "operator.counters",
        )
    )
    started = time.perf_counter()
    while len(core.source.snapshot()["tags"]) < args.tags:
        for _ in range(100):
            core.source.step_once()  # type: ignore[attr-defined]
    ahead = time.perf_counter() - started
    sock = bind("127.0.0.1", 0)
    token = "bench"
    print(f"http://127.0.0.1:{sock.getsockname()[1]}/?token={token} {ahead:.1f}", flush=True)
    app = make_app(core, token, stream_s=1 / args.rate)
    config = uvicorn.Config(app, log_level="warning", access_log=False, lifespan="on")
    uvicorn.Server(config).run(sockets=[sock])


def cpu_seconds(processes: list[psutil.Process]) -> float:
    """User + system seconds of ``processes`` (those gone count 0)."""
    total = 0.0
    for process in processes:
        try:
            times = process.cpu_times()
        except psutil.Error:
            continue
        total += times.user + times.system
    return total


def server_time(base: str) -> float:
    """The server's simulated clock now (``GET /api/state``)."""
    request = urllib.request.Request(f"{base}/api/state", headers={"Authorization": "Bearer bench"})
    with urllib.request.urlopen(request, timeout=10) as answer:
        return float(json.loads(answer.read())["time"])


def percentile(values: list[float], q: float) -> float:
    """The ``q``-th percentile of ``values`` (0 for none)."""
    if not values:
        return 0.0
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q / 100 * len(ordered)))]


def measure(args: argparse.Namespace, url: str) -> dict[str, Any]:
    """Open the page in Chromium and count, for ``--seconds``, what the page and server do."""
    from playwright.sync_api import sync_playwright  # noqa: PLC0415 - the dev extra

    base = url.split("/?", 1)[0]
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=os.fspath(CHROMIUM), headless=True)
        # the page's CSP forbids evaluating strings, which the probe's wrapping needs
        context = browser.new_context(viewport={"width": 1600, "height": 1000}, bypass_csp=True)
        page = context.new_page()
        page.add_init_script(PROBE)
        page.goto(url)
        page.wait_for_function(
            "(n) => Number(document.getElementById('tag-count').dataset.total) >= n",
            arg=args.tags,
        )
        page.evaluate(
            "() => { const b = window.__bench; b.events = 0; b.handling = [];"
            " b.draws = 0; b.drawing = []; b.frames = []; b.long = []; }"
        )
        me = psutil.Process()
        server = [p for p in me.children() if p.pid == args.child_pid]
        chrome = [p for p in me.children(recursive=True) if "chrom" in p.name().lower()]
        cpu_server, cpu_chrome = cpu_seconds(server), cpu_seconds(chrome)
        clock = server_time(base)
        started = time.perf_counter()
        time.sleep(args.seconds)
        wall = time.perf_counter() - started
        cpu_server = cpu_seconds(server) - cpu_server
        cpu_chrome = cpu_seconds(chrome) - cpu_chrome
        now = server_time(base)
        bench = page.evaluate("() => window.__bench")
        rows = int(page.locator("#tag-count").get_attribute("data-total") or 0)
        if args.screenshot:
            page.screenshot(path=os.fspath(args.screenshot))
        browser.close()
    handling = [float(x) for x in bench["handling"]]
    drawing = [float(x) for x in bench["drawing"]]
    frames = [float(x) for x in bench["frames"]]
    return {
        "wall_s": wall,
        "rows": rows,
        "server_cpu_per_s": cpu_server / wall,
        "server_clock_per_s": (now - clock) / wall,
        "browser_cpu_per_s": cpu_chrome / wall,
        "events_per_s": bench["events"] / wall,
        "handling_median_ms": statistics.median(handling) if handling else 0.0,
        "handling_p95_ms": percentile(handling, 95),
        "draws_per_s": bench["draws"] / wall,
        "draw_median_ms": statistics.median(drawing) if drawing else 0.0,
        "draw_p95_ms": percentile(drawing, 95),
        "frame_median_ms": statistics.median(frames) if frames else 0.0,
        "frame_p95_ms": percentile(frames, 95),
        "long_tasks": len(bench["long"]),
        "long_task_max_ms": max(bench["long"], default=0.0),
        "lag_s": now - (bench["lastTime"] or 0.0),
    }


def main() -> None:
    """Parse, start the child server, measure with the browser, record."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--robots", type=int, default=100)
    parser.add_argument("--tags", type=int, default=1000)
    parser.add_argument("--rate", type=float, default=10.0, help="state events a second")
    parser.add_argument("--seconds", type=float, default=20.0, help="the measured window")
    parser.add_argument("--order-interval", type=float, default=0.2, help="seconds per order")
    parser.add_argument("--screenshot", type=Path, help="save the page at the end (PNG)")
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--folder", help=argparse.SUPPRESS)
    parser.add_argument("--child-pid", type=int, help=argparse.SUPPRESS)
    if "--serve" in sys.argv:
        serve(parser.parse_args())
        return
    args, record = begin(parser, __file__)
    import tempfile  # noqa: PLC0415

    with tempfile.TemporaryDirectory() as folder:
        child = subprocess.Popen(
            [
                sys.executable,
                __file__,
                "--serve",
                "--folder",
                folder,
                "--robots",
                str(args.robots),
                "--tags",
                str(args.tags),
                "--rate",
                str(args.rate),
                "--order-interval",
                str(args.order_interval),
                "--seconds",
                str(args.seconds),
            ],
            stdout=subprocess.PIPE,
            text=True,
        )
        try:
            assert child.stdout is not None
            url, ahead = child.stdout.readline().split()
            args.child_pid = child.pid
            print(f"served after stepping {float(ahead):.0f} s ahead to {args.tags} tags")
            found = measure(args, url)
        finally:
            child.terminate()
            child.wait(timeout=10)
    found["step_ahead_s"] = float(ahead)
    interval_ms = 1000 / args.rate
    found["keeps_up"] = bool(
        found["events_per_s"] >= 0.9 * args.rate
        and found["draws_per_s"] >= 0.9 * args.rate
        and found["handling_p95_ms"] + found["draw_p95_ms"] < interval_ms
    )
    for key, value in found.items():
        print(f"{key:22} {value:.3f}" if isinstance(value, float) else f"{key:22} {value}")
    record.row(robots=args.robots, tags=args.tags, rate=args.rate, **found)
    record.summary.update(found)
    record.save()


if __name__ == "__main__":
    main()
