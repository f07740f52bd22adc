"""A 5×5 grid world with a dense distance reward and a small numpy renderer."""

from typing import Any

import gymnasium as gym
import numpy as np

from groupwise.envs.rendering import DEFAULT_FRAME_SIZE
from groupwise.envs.true_reward import TRUE_REWARD_KEY

MOVES = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]], dtype=np.int64)
"""Displacement (dx, dy) of each action: stay, +x, −x, +y, −y."""

BACKGROUND = (255, 255, 255)
GRID_LINES = (170, 170, 170)
TARGET_COLOUR = (46, 160, 67)
AGENT_COLOUR = (31, 91, 200)


def distance_reward(agent: np.ndarray, target: np.ndarray) -> float:
    """``1 / (1 + euclidean distance between agent and target)``: 1 on the target, in (0, 1]."""
    return 1.0 / (1.0 + float(np.linalg.norm(np.asarray(agent) - np.asarray(target))))


def draw_grid(
    size: int, agent: np.ndarray, target: np.ndarray, width: int, height: int
) -> np.ndarray:
    """Draw the grid as a (height, width, 3) uint8 image: white cells with grey lines, the
    target as a green square, the agent as a blue disc on top; +y points up."""
    frame = np.empty((height, width, 3), dtype=np.uint8)
    frame[:] = BACKGROUND
    cell_w, cell_h = width / size, height / size
    rows, cols = np.ogrid[:height, :width]

    def cell_box(cell: np.ndarray, inset: float) -> tuple[int, int, int, int]:
        x, y = int(cell[0]), size - 1 - int(cell[1])
        return (
            round((y + inset) * cell_h),
            round((y + 1 - inset) * cell_h),
            round((x + inset) * cell_w),
            round((x + 1 - inset) * cell_w),
        )

    top, bottom, left, right = cell_box(target, 0.1)
    frame[top:bottom, left:right] = TARGET_COLOUR
    x, y = int(agent[0]), size - 1 - int(agent[1])
    centre_row, centre_col = (y + 0.5) * cell_h, (x + 0.5) * cell_w
    radius = 0.35 * min(cell_w, cell_h)
    disc = ((rows + 0.5 - centre_row) ** 2 + (cols + 0.5 - centre_col) ** 2) <= radius**2
    frame[disc] = AGENT_COLOUR
    for k in range(size + 1):
        row = min(round(k * cell_h), height - 1)
        col = min(round(k * cell_w), width - 1)
        frame[row, :] = GRID_LINES
        frame[:, col] = GRID_LINES
    return frame


class GridWorldEnv(gym.Env[np.ndarray, np.int64]):
    """Move an agent to a target on a `size`×`size` grid; never terminates.

    Observation: float32 Box(4) = (agent x, agent y, target x, target y), cells 0 … size−1.
    Action: Discrete(5) = stay, +x, −x, +y, −y; moves into a wall leave the agent in place.
    Reward (also in ``info["true_reward"]``): `distance_reward` after the move.
    Reset draws distinct agent and target cells from the env's seeded generator;
    ``options={"agent": (x, y), "target": (x, y)}`` places them by hand instead.
    The horizon (1000 steps) comes from the registration's ``max_episode_steps``.
    """

    # Gymnasium declares `metadata` as an instance attribute, so ClassVar would not type-check.
    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 30}  # noqa: RUF012

    def __init__(
        self,
        render_mode: str | None = None,
        size: int = 5,
        width: int = DEFAULT_FRAME_SIZE[0],
        height: int = DEFAULT_FRAME_SIZE[1],
    ) -> None:
        if size < 2:
            raise ValueError(f"grid size must be at least 2, got {size}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"unsupported render_mode {render_mode!r}: use 'rgb_array'")
        self.size = size
        self.render_mode = render_mode
        self.width, self.height = width, height
        self.observation_space = gym.spaces.Box(0.0, float(size - 1), shape=(4,), dtype=np.float32)
        self.action_space = gym.spaces.Discrete(len(MOVES))
        self._agent = np.zeros(2, dtype=np.int64)
        self._target = np.ones(2, dtype=np.int64)

    def _obs(self) -> np.ndarray:
        return np.concatenate([self._agent, self._target]).astype(np.float32)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        options = options or {}
        if "agent" in options or "target" in options:
            self._agent = np.asarray(options["agent"], dtype=np.int64)
            self._target = np.asarray(options["target"], dtype=np.int64)
            if not (self._on_grid(self._agent) and self._on_grid(self._target)):
                raise ValueError(f"agent and target must lie on the {self.size}×{self.size} grid")
        else:
            agent, target = self.np_random.choice(self.size * self.size, size=2, replace=False)
            self._agent = np.array(divmod(int(agent), self.size), dtype=np.int64)
            self._target = np.array(divmod(int(target), self.size), dtype=np.int64)
        return self._obs(), {}

    def _on_grid(self, cell: np.ndarray) -> bool:
        return cell.shape == (2,) and bool(np.all((cell >= 0) & (cell < self.size)))

    def step(self, action: np.int64 | int) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self.action_space.contains(action):
            raise ValueError(f"invalid action {action!r} for {self.action_space}")
        self._agent = np.clip(self._agent + MOVES[int(action)], 0, self.size - 1)
        reward = distance_reward(self._agent, self._target)
        return self._obs(), reward, False, False, {TRUE_REWARD_KEY: reward}

    def render(self) -> np.ndarray | None:
        """A (height, width, 3) uint8 frame, or None without a render mode."""
        if self.render_mode is None:
            return None
        return draw_grid(self.size, self._agent, self._target, self.width, self.height)
