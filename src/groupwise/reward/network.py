"""The reward networks: an input normaliser and K member MLPs evaluated as one (SPEC §3).

Each member is an ordinary MLP (`hidden_sizes` ReLU layers, one scalar reward per step).
The K members keep their weights stacked in (K, in, out) tensors so one batched matmul per
layer evaluates all of them: the PPO reward wrapper calls the ensemble every env step, and
K separate `nn.Sequential` forwards would cost K times the Python and dispatch overhead.
`StackedMLP.member(k)` gives member k back as a plain `nn.Sequential`.
"""

import math
from collections.abc import Callable
from itertools import pairwise
from typing import Literal

import numpy as np
import torch
from torch import Tensor, nn

ACTIVATIONS: dict[str, Callable[[Tensor], Tensor]] = {
    "relu": torch.relu,
    "tanh": torch.tanh,
    "leaky_relu": nn.functional.leaky_relu,
}
"""Hidden-layer nonlinearities by config name (`RewardConfig.activation`)."""

_ACTIVATION_MODULES: dict[str, Callable[[], nn.Module]] = {
    "relu": nn.ReLU,
    "tanh": nn.Tanh,
    "leaky_relu": nn.LeakyReLU,
}


class RunningNorm(nn.Module):
    """Per-feature running mean and variance, and the standardisation they define.

    The statistics change only through `update` / `reset`, never as a side effect of a
    forward pass, so predictions are a pure function of the saved state. Before the first
    update the transform is the identity (mean 0, variance 1).
    """

    mean: Tensor
    var: Tensor
    count: Tensor

    def __init__(self, dim: int, eps: float = 1e-8, clip: float = 10.0) -> None:
        """`dim` features; outputs are clipped to ±`clip` (as SB3's VecNormalize does) so a
        feature that was constant in the training data cannot blow up at prediction time."""
        super().__init__()
        if dim < 1:
            raise ValueError(f"a normaliser needs at least one feature, got {dim}")
        self.dim = dim
        self.eps = eps
        self.clip = clip
        self.register_buffer("mean", torch.zeros(dim))
        self.register_buffer("var", torch.ones(dim))
        self.register_buffer("count", torch.zeros((), dtype=torch.float64))

    def reset(self) -> None:
        """Forget every update: back to the identity transform."""
        self.mean.zero_()
        self.var.fill_(1.0)
        self.count.zero_()

    @torch.no_grad()
    def update(self, x: Tensor | np.ndarray) -> None:
        """Fold the rows of `x` (..., dim) into the statistics (Chan et al.'s parallel merge).

        Raises ValueError when the last axis is not `dim`. An empty batch changes nothing.
        """
        batch = torch.as_tensor(np.asarray(x) if not isinstance(x, Tensor) else x)
        if batch.shape[-1] != self.dim:
            raise ValueError(f"expected {self.dim} features, got shape {tuple(batch.shape)}")
        batch = batch.reshape(-1, self.dim).to(torch.float64)
        n = batch.shape[0]
        if n == 0:
            return
        batch_mean = batch.mean(dim=0)
        batch_var = batch.var(dim=0, unbiased=False)
        count = float(self.count)
        total = count + n
        delta = batch_mean - self.mean.to(torch.float64)
        mean = self.mean.to(torch.float64) + delta * (n / total)
        m2 = self.var.to(torch.float64) * count + batch_var * n + delta**2 * (count * n / total)
        self.mean.copy_(mean)
        self.var.copy_(m2 / total)
        self.count.fill_(total)

    @torch.no_grad()
    def uncentre(self, start: int) -> None:
        """From feature `start` on, scale by the root mean square instead of centring and
        scaling by the sd (a control cost must be 0 at action 0). Second moments merge as
        variances about 0 do, so `update` keeps them exact; call this after each update."""
        tail = slice(start, None)
        self.var[tail] += self.mean[tail].square()
        self.mean[tail] = 0.0

    def forward(self, x: Tensor) -> Tensor:
        """(..., dim) -> (..., dim) standardised and clipped."""
        z = (x - self.mean) * torch.rsqrt(self.var + self.eps)
        return z.clamp(-self.clip, self.clip)


class StackedMLP(nn.Module):
    """K independent MLPs `in_dim → hidden_sizes → 1` whose weights are stacked per layer.

    Initialisation matches `nn.Linear`'s default (weights and biases uniform in
    ±1/sqrt(fan_in)) but draws from an explicit `torch.Generator`, never the global RNG.
    """

    def __init__(
        self,
        members: int,
        in_dim: int,
        hidden_sizes: tuple[int, ...],
        activation: str = "relu",
        generator: torch.Generator | None = None,
    ) -> None:
        """Raises ValueError for fewer than one member, input feature or hidden unit, and
        KeyError for an activation not in `ACTIVATIONS`."""
        super().__init__()
        if members < 1 or in_dim < 1 or any(h < 1 for h in hidden_sizes):
            raise ValueError(
                f"invalid ensemble shape: {members} members, {in_dim} inputs, {hidden_sizes}"
            )
        if activation not in ACTIVATIONS:
            raise KeyError(f"unknown activation {activation!r}; known: {sorted(ACTIVATIONS)}")
        self.members = members
        self.in_dim = in_dim
        self.hidden_sizes = tuple(hidden_sizes)
        self.activation = activation
        self._act = ACTIVATIONS[activation]
        widths = [in_dim, *self.hidden_sizes, 1]
        self.weights = nn.ParameterList(
            nn.Parameter(torch.empty(members, fan_in, fan_out))
            for fan_in, fan_out in pairwise(widths)
        )
        # Biases are (K, 1, out) so `baddbmm` broadcasts them over the batch without a copy.
        self.biases = nn.ParameterList(
            nn.Parameter(torch.empty(members, 1, fan_out)) for fan_out in widths[1:]
        )
        # Plain references to the same Parameter objects: iterating a ParameterList costs
        # ~12 µs, half a whole forward pass at PPO batch sizes. Loading a state dict,
        # pickling and deep-copying keep the objects (and so these references) intact.
        self._layers = tuple(zip(self.weights, self.biases, strict=True))
        self.reset_parameters(generator)

    @torch.no_grad()
    def reset_parameters(self, generator: torch.Generator | None = None) -> None:
        """Redraw every weight from `generator` (a fixed-seed one when None)."""
        if generator is None:
            generator = torch.Generator().manual_seed(0)
        for weight, bias in self._layers:
            bound = 1.0 / math.sqrt(weight.shape[1])
            weight.copy_((torch.rand(weight.shape, generator=generator) * 2 - 1) * bound)
            bias.copy_((torch.rand(bias.shape, generator=generator) * 2 - 1) * bound)

    def forward(self, x: Tensor) -> Tensor:
        """Per-member scalar outputs.

        x: (N, in_dim), the same inputs for every member, or (K, N, in_dim), one batch per
        member. Returns (K, N).
        """
        h = x.expand(self.members, *x.shape) if x.dim() == 2 else x
        *hidden, (weight, bias) = self._layers
        for w, b in hidden:
            h = self._act(torch.baddbmm(b, h, w))
        return torch.baddbmm(bias, h, weight).squeeze(-1)

    def l2_penalty(self) -> Tensor:
        """(K,) sum of squared weights (biases excluded) of each member."""
        return sum((w.square().sum(dim=(1, 2)) for w, _ in self._layers), torch.zeros(self.members))

    def member(self, k: int) -> nn.Sequential:
        """A detached copy of member k as an ordinary `nn.Sequential` of `nn.Linear` layers."""
        if not 0 <= k < self.members:
            raise IndexError(f"member {k} of an ensemble of {self.members}")
        layers: list[nn.Module] = []
        last = len(self._layers) - 1
        for i, (weight, bias) in enumerate(self._layers):
            linear = nn.Linear(weight.shape[1], weight.shape[2])
            with torch.no_grad():
                linear.weight.copy_(weight[k].T)
                linear.bias.copy_(bias[k, 0])
            layers.append(linear)
            if i < last:
                layers.append(_ACTIVATION_MODULES[self.activation]())
        return nn.Sequential(*layers)


class QuadraticCost(nn.Module):
    """K members' control cost −Σ_i c_i z_i² over `dims` features, c_i = softplus(w_i) ≥ 0."""

    def __init__(self, members: int, dims: int, initial: float = 0.01) -> None:
        """Every c_i starts at `initial` (> 0)."""
        super().__init__()
        self.members = members
        self.raw = nn.Parameter(torch.full((members, 1, dims), math.log(math.expm1(initial))))

    def forward(self, z: Tensor) -> Tensor:
        """z: (N, dims) or (K, N, dims). Returns (K, N)."""
        return -(nn.functional.softplus(self.raw) * z.square()).sum(dim=-1)

    def l2_penalty(self) -> Tensor:
        """(K,) zeros: the costs are not weights to shrink (shrinking w raises c to 0.69)."""
        return torch.zeros(self.members)


class AdditiveMLP(nn.Module):
    """K members r(x) = f(x[:split]) + g(x[split:]): one `StackedMLP` over the first `split`
    features (the observation) and, over the rest (the action), another `StackedMLP`
    (`second="mlp"`) or a `QuadraticCost` (`second="cost"`), summed.

    The same interface as `StackedMLP` (forward, `l2_penalty`, `members`), so training
    and prediction take either. No term can depend on both parts at once.
    """

    def __init__(
        self,
        members: int,
        in_dim: int,
        split: int,
        hidden_sizes: tuple[int, ...],
        activation: str = "relu",
        generator: torch.Generator | None = None,
        second: Literal["mlp", "cost"] = "mlp",
    ) -> None:
        """Raises ValueError unless 0 < split < in_dim (and as `StackedMLP` does)."""
        super().__init__()
        if not 0 < split < in_dim:
            raise ValueError(f"cannot split {in_dim} features after {split}")
        self.members = members
        self.in_dim = in_dim
        self.split = split
        self.first = StackedMLP(members, split, hidden_sizes, activation, generator)
        self.second: StackedMLP | QuadraticCost = (
            StackedMLP(members, in_dim - split, hidden_sizes, activation, generator)
            if second == "mlp"
            else QuadraticCost(members, in_dim - split)
        )

    def forward(self, x: Tensor) -> Tensor:
        """x: (N, in_dim) or (K, N, in_dim). Returns (K, N)."""
        return self.first(x[..., : self.split]) + self.second(x[..., self.split :])

    def l2_penalty(self) -> Tensor:
        """(K,) sum of squared weights (biases excluded) of each member, both terms."""
        return self.first.l2_penalty() + self.second.l2_penalty()


def member_mlp(
    members: int,
    in_dim: int,
    hidden_sizes: tuple[int, ...],
    activation: str = "relu",
    generator: torch.Generator | None = None,
    split: int | None = None,
    action_term: Literal["joint", "additive", "cost"] = "joint",
) -> StackedMLP | AdditiveMLP:
    """The members' MLPs: one over all features ("joint", or no `split`), or split after
    `split` features into an `AdditiveMLP` with an MLP ("additive") or a control cost
    ("cost") over the rest."""
    if split is None or action_term == "joint":
        return StackedMLP(members, in_dim, hidden_sizes, activation, generator)
    second: Literal["mlp", "cost"] = "mlp" if action_term == "additive" else "cost"
    return AdditiveMLP(members, in_dim, split, hidden_sizes, activation, generator, second)


class RewardNet(nn.Module):
    """Normaliser then stacked MLP: features (..., in_dim) -> per-member rewards (K, ...)."""

    def __init__(
        self,
        members: int,
        in_dim: int,
        hidden_sizes: tuple[int, ...],
        activation: str = "relu",
        generator: torch.Generator | None = None,
        split: int | None = None,
        action_term: Literal["joint", "additive", "cost"] = "joint",
    ) -> None:
        """`split` and `action_term`: the members' form (`member_mlp`)."""
        super().__init__()
        self.norm = RunningNorm(in_dim)
        self.mlp = member_mlp(
            members, in_dim, hidden_sizes, activation, generator, split, action_term
        )

    def forward(self, x: Tensor) -> Tensor:
        """x: (N, in_dim) shared by all members, or (K, N, in_dim). Returns (K, N)."""
        return self.mlp(self.norm(x))
