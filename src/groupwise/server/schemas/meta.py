"""The envs a session can use, and the server's health."""

from typing import Literal

from pydantic import Field

from groupwise.server.schemas.base import Out


class TargetOut(Out):
    """A case study's target: the reward-free behaviour a target env scores
    (`groupwise.envs.targets.Target`)."""

    name: str = Field(examples=["hopper-backflip"])
    base: str = Field(description="the groupwise env it modifies", examples=["Hopper"])
    unit: str = Field(description="what an episode's score counts", examples=["backward turns"])
    threshold: float = Field(description="an episode succeeds when its score reaches this")
    stretch: float = Field(description="the more ambitious level")
    success: str = Field(
        description="when an episode succeeds, in words (the threshold in it)",
        examples=["a split held ≥ 1 s"],
    )
    description: str = Field(description="the definition in one paragraph")


class EnvOut(Out):
    """An env a session can use by `name`; any other registered Gymnasium id works too."""

    name: str = Field(examples=["Hopper"], description="what POST /api/sessions takes as env")
    gym_id: str = Field(examples=["groupwise/Hopper-v0"])
    kind: Literal["env", "target"] = Field(
        description="env: one of the six fixed-horizon envs; target: a case study's "
        "reward-free env, scored by its target"
    )
    horizon: int = Field(description="steps per episode")
    clip_seconds: float = Field(description="simulated seconds a behaviour covers by default")
    description: str = Field(description="how it differs from the standard env, in one line")
    target: TargetOut | None = None


class Health(Out):
    status: Literal["ok"] = "ok"
    worker_pid: int | None = Field(description="the training worker's process id, if running")
    worker_pids: list[int] = Field(
        default_factory=list,
        description="every running training worker's process id (`serve --training-workers`)",
    )
