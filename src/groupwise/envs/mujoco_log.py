"""MuJoCo's warnings through Python logging, each distinct one once per process.

MuJoCo prints its warnings to stderr from C. Gymnasium's ``half_cheetah.xml`` uses a compiler
attribute MuJoCo 4 deprecates (``settotalmass``), so every HalfCheetah model load printed
"WARNING: compiler attribute 'settotalmass' is deprecated …": dozens of identical lines per
study cell, one per env made. `log_mujoco_warnings` routes them to the ``groupwise.mujoco``
logger instead: the first of each text at INFO, repeats at DEBUG.
"""

import logging
from collections.abc import Callable

log = logging.getLogger("groupwise.mujoco")

_seen: set[str] = set()


def _log_warning(message: str) -> None:
    text = message.strip()
    if text in _seen:
        log.debug("MuJoCo: %s", text)
    else:
        _seen.add(text)
        log.info("MuJoCo: %s (further repeats at DEBUG)", text)


def log_mujoco_warnings() -> None:
    """Route MuJoCo's warnings to the ``groupwise.mujoco`` logger in this process.

    Does nothing when MuJoCo is not installed or when a warning handler is already set (a
    user's own, or ours): the first handler stands.
    """
    try:
        import mujoco
    except ImportError:
        return
    current: Callable[[str], None] | None = mujoco.get_mju_user_warning()
    if current is None:
        mujoco.set_mju_user_warning(_log_warning)
