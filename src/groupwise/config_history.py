"""Old config layouts a run's config.json, a checkpoint or a stored session may have: the
fields renamed since (read under their new name) and those of mechanisms removed since
(dropped, with a warning when one was in use). `config.RunConfig.from_dict` and
`RunConfig.merged` read every config through `legacy_loop_fields_moved` and
`removed_dropped`."""

import logging
from typing import Any

log = logging.getLogger("groupwise.config")


LEGACY_LOOP_FIELDS: dict[str, tuple[str, str]] = {
    "noise_sigma": ("teacher", "noise_sigma"),
    "interactive_gap": ("teacher", "interactive_gap"),
    "interactive_clear": ("teacher", "interactive_clear"),
    "teacher_gamma": ("teacher", "gamma"),
    "teacher_mistake": ("teacher", "mistake"),
    "teacher_skip_quantile": ("teacher", "skip_quantile"),
    "teacher_equal_fraction": ("teacher", "equal_fraction"),
    "oracle": ("loop", "decision_maker"),
}
"""Old `LoopConfig` field → the section and field that hold it now: issue 19 moved the
teacher's fields out of the loop into `TeacherConfig`; issue 38 renamed "oracle" to
`decision_maker` (one word for one concept)."""


REMOVED_FIELDS: dict[str, dict[str, Any]] = {
    "reward": {
        "exploration_bonus": 0.0,
        "pessimism": 0.0,
        "exploration_decay": 0.5,
        "reset_every": None,
        "reset_margin": None,
        "crops": 0,
        "pseudo_labels": None,
    },
    "loop": {
        "pool_variants_greedy": False,
        "pool_lookahead": 0,
        "adopt_variants": False,
        "suggestion_rank": "variance",
        "coverage_share": 0.0,
    },
    "training": {"continue_from": "last", "continue_episodes": 3},
}
"""Section → field → its default: fields of mechanisms that measured no gain, removed in
issues 38 and 41 (their results, commands and the commit with their code:
docs/case-studies.md, "Measured and removed"). Configs of older runs still load without
them."""


def removed_dropped(data: dict[str, Any]) -> dict[str, Any]:
    """`data` without `REMOVED_FIELDS`; a warning names those that were not their default
    (the run used a mechanism that is gone, so it cannot be repeated as it ran)."""
    dropped: dict[str, Any] = {}
    cleaned = dict(data)
    for section, removed in REMOVED_FIELDS.items():
        fields = data.get(section)
        if not isinstance(fields, dict) or not fields.keys() & removed.keys():
            continue
        cleaned[section] = {k: v for k, v in fields.items() if k not in removed}
        dropped |= {
            f"{section}.{k}": v for k, v in fields.items() if k in removed and v != removed[k]
        }
    if dropped:
        used = ", ".join(f"{key}={value!r}" for key, value in sorted(dropped.items()))
        log.warning(
            "config uses removed mechanisms (%s): read without them; docs/case-studies.md, "
            "'Measured and removed', names the commit that has their code",
            used,
        )
    return cleaned


def legacy_loop_fields_moved(data: dict[str, Any]) -> dict[str, Any]:
    """`data` with the fields of an old layout's "loop" (`LEGACY_LOOP_FIELDS`) under the
    section and name that hold them now.

    Raises:
        ValueError: a field is given under both its old and its new name.
    """
    loop = data.get("loop")
    if not isinstance(loop, dict) or not loop.keys() & LEGACY_LOOP_FIELDS.keys():
        return data
    sections: dict[str, dict[str, Any]] = {
        "loop": {key: value for key, value in loop.items() if key not in LEGACY_LOOP_FIELDS}
    }
    for key, value in loop.items():
        if key not in LEGACY_LOOP_FIELDS:
            continue
        section, name = LEGACY_LOOP_FIELDS[key]
        if section not in sections:
            given = data.get(section, {})
            if not isinstance(given, dict):
                return data  # validation names the bad value
            sections[section] = dict(given)
        if name in sections[section]:
            raise ValueError(f"{section}.{name} is given twice: also as loop.{key}, its old name")
        sections[section][name] = value
    return {**data, **sections}
