#!/usr/bin/env bash
# Installs the CPU build of PyTorch into the environment of a Python interpreter:
#   scripts/install-torch.sh [python]        (default: python3)
# An unpinned `pip install torch` on Linux pulls gigabytes of CUDA wheels, so this asks for
# the CPU build by its local version label, torch==$TORCH_VERSION+cpu: first from pip's
# configured sources (on the project's machines a wheel on local disk), and only when it is
# not found there from PyTorch's CPU index (with PyPI for torch's own dependencies). On macOS
# PyPI's torch is the CPU build and has no +cpu label. Does nothing when it is installed.
set -euo pipefail

python=${1:-python3}
version=${TORCH_VERSION:-2.13.0}
if [ "$(uname -s)" = Darwin ]; then want=$version; else want=$version+cpu; fi
CPU_INDEX=https://download.pytorch.org/whl/cpu

have=$("$python" -c 'import importlib.metadata as m
try:
    print(m.version("torch"))
except m.PackageNotFoundError:
    pass')
if [ "$have" = "$want" ]; then
  echo "torch $have is installed"
  exit 0
fi

log=$(mktemp)
trap 'rm -f "$log"' EXIT
echo "installing torch==$want"
if "$python" -m pip install -q --timeout 30 "torch==$want" >"$log" 2>&1; then
  exit 0
fi
if [ "$want" = "$version" ]; then  # macOS: nowhere else to look
  cat "$log" >&2
  exit 1
fi
echo "torch==$want is not in pip's sources; trying PyTorch's CPU index ($CPU_INDEX)"
# --retries 0 and a short --timeout: an unreachable index fails in seconds, never hangs
if ! "$python" -m pip install -q --timeout 20 --retries 0 \
  --index-url "$CPU_INDEX" --extra-index-url https://pypi.org/simple "torch==$want"; then
  echo "--- the first attempt (pip's configured sources) said:" >&2
  tail -n 5 "$log" >&2
  echo "could not install torch==$want; install the CPU build of torch $version by hand" >&2
  echo "(https://pytorch.org/get-started/locally/), then run make again" >&2
  exit 1
fi
