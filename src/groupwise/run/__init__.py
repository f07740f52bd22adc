"""A run of the RLHF loop (SPEC §3): its state and directory (`run.Run`), the round in two
halves (`round.begin_round` → a teacher answers → `round.end_round`), the rounds of a
headless run (`headless`), the final phase and the take-away agent (`final`), and the
library's `PreferenceComparisons`.
"""
