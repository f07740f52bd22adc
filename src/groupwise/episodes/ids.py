"""Behaviour i of a pool is named ``b<i>`` wherever a person or a file sees it (the tree's
leaf ids, the page, the database, exports); `behaviour_id` and `behaviour_index` are the
only places that spell that name."""

BEHAVIOUR_PREFIX = "b"


def behaviour_id(index: int) -> str:
    """The name of pool behaviour `index`: ``b<index>``."""
    return f"{BEHAVIOUR_PREFIX}{int(index)}"


def behaviour_index(name: str) -> int:
    """The pool index of behaviour `name` (``b<index>``).

    Raises:
        ValueError: `name` is not a behaviour name.
    """
    digits = name[len(BEHAVIOUR_PREFIX) :]
    if not name.startswith(BEHAVIOUR_PREFIX) or not digits.isdigit():
        raise ValueError(f"{name!r} is not a behaviour id (b<index>)")
    return int(digits)
