#!/usr/bin/env bash
# Checks that groupwise installs the way a user installs it and serves its web UI:
#   scripts/check-install.sh            (PYTHON=python3.12 scripts/check-install.sh for another)
# 1. builds the web UI into the package (`make web`: src/groupwise/static/);
# 2. copies the checkout (tracked and untracked files that git does not ignore, plus the UI
#    build) to a temporary directory, so no build/ left in the checkout can hide a missing file;
# 3. makes a fresh venv there: the CPU torch (scripts/install-torch.sh), then `pip install .`
#    (the core alone: every core module must import, and `groupwise --help` run), then
#    `pip install '.[app]'`;
# 4. starts `groupwise serve` on a free port with a temporary data directory, fetches `/`
#    (the page must hold the app's root element) and the script it loads, and stops it.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
started=$SECONDS

tmp=$(mktemp -d "${TMPDIR:-/tmp}/groupwise-check-install.XXXXXX")
server=
cleanup() {
  if [ -n "$server" ] && kill -0 "$server" 2>/dev/null; then
    kill -TERM -- "-$server" 2>/dev/null || true
    for _ in $(seq 20); do kill -0 "$server" 2>/dev/null || break; sleep 0.5; done
    kill -KILL -- "-$server" 2>/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT

step() { echo "check-install: $* ($((SECONDS - started)) s)"; }
quiet() {  # runs a command, showing its output only when it fails
  local log="$tmp/step.log"
  if ! "$@" >"$log" 2>&1; then
    cat "$log" >&2
    echo "check-install: FAILED: $*" >&2
    exit 1
  fi
}

step "building the web UI into the package"
make -s web
[ -f src/groupwise/static/index.html ] || { echo "no src/groupwise/static/index.html" >&2; exit 1; }

step "copying the checkout to $tmp/src"
mkdir "$tmp/src"
git ls-files -z --cached --others --exclude-standard |
  "$PYTHON" -c 'import os, sys
print("\0".join(p for p in sys.stdin.read().split("\0") if p and os.path.isfile(p)), end="")' |
  tar --null -T - -cf - | tar -xf - -C "$tmp/src"
cp -R src/groupwise/static "$tmp/src/src/groupwise/static"

step "a fresh venv with the CPU torch"
"$PYTHON" -m venv "$tmp/venv"
py=$tmp/venv/bin/python
quiet bash scripts/install-torch.sh "$py"

step "pip install . (the core alone)"
quiet "$py" -m pip install "$tmp/src"
(cd "$tmp" && quiet "$py" - <<'EOF'
import importlib
import pkgutil

import groupwise

extras = ("groupwise.server", "groupwise.storage", "groupwise.worker", "groupwise.study")
names = [m.name for m in pkgutil.walk_packages(groupwise.__path__, "groupwise.")]
core = [n for n in names if not n.startswith(extras)]
for name in core:
    importlib.import_module(name)
print(f"{len(core)} core modules import without the extras")
EOF
)
quiet "$tmp/venv/bin/groupwise" --help

step "pip install '.[app]'"
quiet "$py" -m pip install "$tmp/src[app]"
static=$(cd "$tmp" && "$py" -c 'from groupwise.server.config import default_static_dir as d; print(d())')
case "$static" in "$tmp/venv/"*) ;; *) echo "the UI is served from $static, not the venv" >&2; exit 1 ;; esac
[ -f "$static/index.html" ] || { echo "the installed package has no $static/index.html" >&2; exit 1; }

step "groupwise serve"
log=$tmp/serve.log
# its own process group (setsid), so stopping it stops its training worker too
(cd "$tmp" && exec setsid "$tmp/venv/bin/groupwise" serve --env GridWorld --data "$tmp/data" \
  --port 0 --pool-size 8 >"$log" 2>&1) &
server=$!
url=
for _ in $(seq 120); do
  url=$(grep -o 'http://127\.0\.0\.1:[0-9]*/' "$log" | head -n 1 || true)
  [ -n "$url" ] && break
  kill -0 "$server" 2>/dev/null || break
  sleep 0.5
done
if [ -z "$url" ]; then
  cat "$log" >&2
  echo "check-install: FAILED: groupwise serve printed no URL" >&2
  exit 1
fi
"$py" - "$url" <<'EOF' || { cat "$log" >&2; echo "check-install: FAILED: $url" >&2; exit 1; }
import re
import sys
import time
import urllib.request

url = sys.argv[1]


def get(path: str) -> bytes:
    for attempt in range(20):
        try:
            with urllib.request.urlopen(url + path, timeout=30) as response:
                return response.read()
        except OSError:
            if attempt == 19:
                raise
            time.sleep(0.5)
    raise AssertionError


page = get("").decode()
assert '<div id="app">' in page, f"no app root element in the page at {url}:\n{page[:500]}"
script = re.search(r'src="\./(assets/[^"]+\.js)"', page)
assert script, "the page loads no script from assets/"
assert len(get(script.group(1))) > 1000, f"{script.group(1)} is empty"
print(f"{url} serves the web UI ({script.group(1)})")
EOF
kill -TERM -- "-$server" 2>/dev/null || true
for _ in $(seq 20); do kill -0 "$server" 2>/dev/null || break; sleep 0.5; done
if kill -0 "$server" 2>/dev/null; then
  echo "check-install: FAILED: groupwise serve did not stop within 10 s of SIGTERM" >&2
  exit 1
fi
step "passed"
