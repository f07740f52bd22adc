"""groupwise: reinforcement learning from human feedback with interactive groupwise comparison."""

__version__ = "0.1.0"
