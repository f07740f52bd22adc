"""Benchmark: the exploration view in Chromium (SPEC §9; targets from issue 6).

Times, for a synthetic round of N leaves with 100 suggestion and 400 history edges, in the
app's left column at 1366 × 768:
- first render: the view built from nothing, script plus style and layout; until the next
  frame has been painted (the arcs); until the frame after, with the edges, was painted
  (edges go to a canvas one frame after the arcs);
- selection update: new groups → arc tints and labels, script plus style and layout
  (median and 95th percentile of 40), and the mean frame interval when one selection
  changes every frame (16.7 ms means every update fits in its frame);
- hover: the edges of the hovered leaf highlighted (a small canvas redraw; the others dim
  through CSS opacity), and the frame interval with one hover per frame;
- zoom (issue 40): a wheel step of d3-zoom on the chart (the drawn layers' CSS transform,
  script plus style and layout; median and 95th percentile of 60), the mean frame interval
  with one wheel step per frame, in to ×5.5 and back out, and the time from the gesture's
  end to the frame with the arcs and edges drawn afresh at its zoom.
Targets: first render < 100 ms and updates < 16 ms at 200 leaves; 1000 leaves usable.

Then the whole app on the same fake server (`bench.html?demo=groupwise`'s), issue 22 item 6:
time to the round on screen (arcs and edges painted), a click's and a hover's render (the
app renders once per frame: timed from the start of that frame to the end of its layout),
and how many clips are loaded — at load those of the first suggestion's groups, one for a
hovered leaf, up to three medoids for a hovered cluster, none once the pointer left — and
how many clip and poster requests the run made (30 clicks, 30 hovers sweeping over leaves,
then one leaf and one cluster hovered long enough for their preview). Clips and posters are
one real 240 × 240 clip and its JPEG poster, served under clips/ as the server would.

It builds and serves `web/dist-bench` (the dev-only `bench.html`, no server needed) and drives
Debian's Chromium with Playwright for Python (no browser download).

    python benchmarks/web_render.py [--leaves 200 1000] [--repeats 3] [--chromium /usr/bin/chromium]
"""

import argparse
import functools
import http.server
import os
import socketserver
import statistics
import subprocess
import sys
import tempfile
import threading
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

WEB = Path(__file__).resolve().parents[1] / "web"
BENCH_DIST = WEB / "dist-bench"
ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
COLUMNS = [
    ("leaves", "leaves", "{:d}"),
    ("arcs", "arcs", "{:d}"),
    ("firstRenderMs", "first render", "{:.1f}"),
    ("firstPaintMs", "arcs painted", "{:.1f}"),
    ("edgesPaintMs", "edges painted", "{:.1f}"),
    ("updateMedianMs", "update (median)", "{:.2f}"),
    ("updateP95Ms", "update (p95)", "{:.2f}"),
    ("frameMs", "frame, 1 update/frame", "{:.1f}"),
    ("hoverMedianMs", "hover", "{:.2f}"),
    ("hoverFrameMs", "frame, 1 hover/frame", "{:.1f}"),
]
ZOOM_COLUMNS = [
    ("leaves", "leaves", "{:d}"),
    ("zoomStepMedianMs", "zoom step (median)", "{:.2f}"),
    ("zoomStepP95Ms", "zoom step (p95)", "{:.2f}"),
    ("zoomFrameMs", "frame, 1 zoom step/frame", "{:.1f}"),
    ("zoomSettleMs", "redrawn after the gesture", "{:.1f}"),
]
APP_COLUMNS = [
    ("leaves", "leaves", "{:d}"),
    ("onScreenMs", "on screen", "{:.0f}"),
    ("selectMedianMs", "click (median)", "{:.2f}"),
    ("selectP95Ms", "click (p95)", "{:.2f}"),
    ("hoverMedianMs", "hover (median)", "{:.2f}"),
    ("videosAtLoad", "videos at load", "{:d}"),
    ("previewLeafVideos", "videos, leaf hovered", "{:d}"),
    ("previewClusterVideos", "videos, cluster hovered", "{:d}"),
    ("videosAfterLeave", "videos after leaving", "{:d}"),
    ("videosMax", "most videos at once", "{:d}"),
    ("posterRequests", "poster requests", "{:d}"),
    ("clipRequests", "clip requests", "{:d}"),
]


def _newest(path: Path) -> float:
    return max((p.stat().st_mtime for p in path.rglob("*") if p.is_file()), default=0.0)


def ensure_build() -> None:
    """Builds web/dist-bench when it is missing or older than the sources."""
    page = BENCH_DIST / "bench.html"
    sources = max(
        _newest(WEB / "src"), _newest(WEB / "bench"), (WEB / "bench.html").stat().st_mtime
    )
    if page.exists() and page.stat().st_mtime >= sources:
        return
    if not (WEB / "node_modules").is_dir():
        raise SystemExit("web/node_modules is missing: run `cd web && npm ci` first")
    subprocess.run(["npm", "run", "--silent", "build:bench"], cwd=WEB, check=True)


def clip_files(directory: Path) -> dict[str, bytes]:
    """One real clip (47 frames of 240 × 240, as a 1.5 s Hopper behaviour) and its poster."""
    import numpy as np

    from groupwise.clips.video import encode_mp4, poster_bytes

    rng = np.random.default_rng(0)
    frames = np.repeat(rng.integers(0, 256, (47, 30, 30, 3), dtype=np.uint8), 8, axis=1)
    frames = np.ascontiguousarray(np.repeat(frames, 8, axis=2))
    encode_mp4(frames, directory / "clip.mp4")
    return {".mp4": (directory / "clip.mp4").read_bytes(), ".jpg": poster_bytes(frames[23])}


@contextmanager
def serve(
    directory: Path, clips: dict[str, bytes] | None = None
) -> Iterator[tuple[str, Counter[str]]]:
    """Serves `directory`, and `clips` (by file ending) at any path under /clips/; yields the
    base URL and the requests for clips, counted by ending."""
    requests: Counter[str] = Counter()
    types = {".mp4": "video/mp4", ".jpg": "image/jpeg"}

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args: Any) -> None:
            pass

        def do_GET(self) -> None:
            if not self.path.startswith("/clips/"):
                super().do_GET()
                return
            ending = Path(self.path).suffix
            requests[ending] += 1
            body = (clips or {}).get(ending)
            if body is None:
                self.send_error(404)
                return
            self.send_response(200)
            self.send_header("Content-Type", types[ending])
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")  # every load counts
            self.end_headers()
            with suppress(ConnectionError):  # a video unloaded while it loaded
                self.wfile.write(body)

    class Server(socketserver.ThreadingTCPServer):
        allow_reuse_address = True
        daemon_threads = True

    handler = functools.partial(Quiet, directory=str(directory))
    with Server(("127.0.0.1", 0), handler) as httpd:
        thread = threading.Thread(target=httpd.serve_forever, daemon=True)
        thread.start()
        try:
            yield f"http://127.0.0.1:{httpd.server_address[1]}", requests
        finally:
            httpd.shutdown()


Column = tuple[str, str, str]


def _medians(results: list[dict[str, float]], columns: list[Column]) -> dict[str, float]:
    return {key: statistics.median(r[key] for r in results) for key, _, _ in columns}


def run(
    sizes: list[int], repeats: int, chromium: str
) -> tuple[list[dict[str, float]], list[dict[str, float]]]:
    """Medians over `repeats` of the view's timings and of the app's, one row per size."""
    from playwright.sync_api import sync_playwright

    ensure_build()
    rows, app_rows = [], []
    with tempfile.TemporaryDirectory() as tmp:
        clips = clip_files(Path(tmp))
    with serve(BENCH_DIST, clips) as (url, requests), sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=ARGS)
        page = browser.new_page(viewport={"width": 1366, "height": 768})
        for n in sizes:
            results, app = [], []
            for _ in range(repeats):
                page.goto(f"{url}/bench.html")
                page.wait_for_function("window.bench !== undefined")
                results.append(page.evaluate("(n) => window.bench.run(n, 100, 400)", n))
                page.goto(f"{url}/bench.html")
                page.wait_for_function("window.bench !== undefined")
                requests.clear()
                result = page.evaluate("(n) => window.bench.app(n)", n)
                result["posterRequests"] = requests[".jpg"]
                result["clipRequests"] = requests[".mp4"]
                app.append(result)
            rows.append(_medians(results, COLUMNS + ZOOM_COLUMNS[1:]))
            app_rows.append(_medians(app, APP_COLUMNS))
        browser.close()
    return rows, app_rows


def table(rows: list[dict[str, float]], columns: list[Column] = COLUMNS) -> str:
    heads = [head for _, head, _ in columns]
    cells = [
        [fmt.format(int(row[key]) if fmt == "{:d}" else row[key]) for key, _, fmt in columns]
        for row in rows
    ]
    widths = [max(len(h), *(len(c[i]) for c in cells)) for i, h in enumerate(heads)]

    def line(values: list[str]) -> str:
        return "| " + " | ".join(v.rjust(w) for v, w in zip(values, widths, strict=True)) + " |"

    out = [line(heads), "|" + "|".join("-" * (w + 2) for w in widths) + "|"]
    out += [line(c) for c in cells]
    return "\n".join(out)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--leaves", "--sizes", dest="sizes", type=int, nargs="+", default=[200, 1000]
    )
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--chromium", default=os.environ.get("GROUPWISE_CHROMIUM", "/usr/bin/chromium")
    )
    args = parser.parse_args([] if argv is None else argv)
    rows, app_rows = run(args.sizes, args.repeats, args.chromium)
    print(
        "Exploration view, 100 suggestion + 400 history edges, Chromium (software raster),"
        " 1366 × 768; all times in ms:"
    )
    print(table(rows))
    print("targets: first render < 100 ms and update < 16 ms at 200 leaves")
    print("\nZooming the chart (wheel steps of d3-zoom; arcs and edges redrawn at the end); ms:")
    print(table(rows, ZOOM_COLUMNS))
    print("target (issue 40): a zoom step within its frame (16.7 ms) at 1,000 leaves")
    print("\nThe whole app on the fake server (posters; clips only when asked for); ms:")
    print(table(app_rows, APP_COLUMNS))
    print("target (issue 22): click and hover ≤ 16 ms median at 1,000 leaves")


if __name__ == "__main__":
    main(sys.argv[1:])
