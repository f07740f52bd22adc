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
  through CSS opacity), and the frame interval with one hover per frame.
Targets: first render < 100 ms and updates < 16 ms at 200 leaves; 1000 leaves usable.

It builds and serves `web/dist-bench` (the dev-only `bench.html`, no server needed) and drives
Debian's Chromium with Playwright for Python (no browser download).

    python benchmarks/web_render.py [--sizes 200 1000] [--repeats 3] [--chromium /usr/bin/chromium]
"""

import argparse
import functools
import http.server
import os
import socketserver
import statistics
import subprocess
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
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


def _newest(path: Path) -> float:
    return max((p.stat().st_mtime for p in path.rglob("*") if p.is_file()), default=0.0)


def ensure_build() -> None:
    """Builds web/dist-bench when it is missing or older than the sources."""
    page = BENCH_DIST / "bench.html"
    sources = max(_newest(WEB / "src"), (WEB / "bench.html").stat().st_mtime)
    if page.exists() and page.stat().st_mtime >= sources:
        return
    if not (WEB / "node_modules").is_dir():
        raise SystemExit("web/node_modules is missing: run `cd web && npm ci` first")
    subprocess.run(["npm", "run", "--silent", "build:bench"], cwd=WEB, check=True)


@contextmanager
def serve(directory: Path) -> Iterator[str]:
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args: Any) -> None:
            pass

    class Server(socketserver.ThreadingTCPServer):
        allow_reuse_address = True
        daemon_threads = True

    handler = functools.partial(Quiet, directory=str(directory))
    with Server(("127.0.0.1", 0), handler) as httpd:
        thread = threading.Thread(target=httpd.serve_forever, daemon=True)
        thread.start()
        try:
            yield f"http://127.0.0.1:{httpd.server_address[1]}"
        finally:
            httpd.shutdown()


def run(sizes: list[int], repeats: int, chromium: str) -> list[dict[str, float]]:
    from playwright.sync_api import sync_playwright

    ensure_build()
    rows = []
    with serve(BENCH_DIST) as url, sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=ARGS)
        page = browser.new_page(viewport={"width": 1366, "height": 768})
        for n in sizes:
            results = []
            for _ in range(repeats):
                page.goto(f"{url}/bench.html")
                page.wait_for_function("window.bench !== undefined")
                results.append(page.evaluate("(n) => window.bench.run(n, 100, 400)", n))
            rows.append({key: statistics.median(r[key] for r in results) for key, _, _ in COLUMNS})
        browser.close()
    return rows


def table(rows: list[dict[str, float]]) -> str:
    heads = [head for _, head, _ in COLUMNS]
    cells = [
        [fmt.format(int(row[key]) if fmt == "{:d}" else row[key]) for key, _, fmt in COLUMNS]
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
    parser.add_argument("--sizes", type=int, nargs="+", default=[200, 1000])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--chromium", default=os.environ.get("GROUPWISE_CHROMIUM", "/usr/bin/chromium")
    )
    args = parser.parse_args([] if argv is None else argv)
    rows = run(args.sizes, args.repeats, args.chromium)
    print(
        "Exploration view, 100 suggestion + 400 history edges, Chromium (software raster),"
        " 1366 × 768; all times in ms:"
    )
    print(table(rows))
    print("targets: first render < 100 ms and update < 16 ms at 200 leaves")


if __name__ == "__main__":
    main(sys.argv[1:])
