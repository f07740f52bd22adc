"""Settings every test process shares."""

import torch

# Tiny nets: torch's intra-op threads only contend with pytest-xdist's other worker (see cli.py).
torch.set_num_threads(1)
