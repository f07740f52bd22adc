"""One peer-benchmark cell of HumanCompatibleAI `imitation` (run by `benchmarks/peer.py` in
imitation's own venv: it pins gymnasium 0.29 and Stable-Baselines3 2.2, so nothing of
groupwise is imported here except, for groupwise's envs, their env modules).

    python benchmarks/peer_imitation.py '<cell spec JSON>'   → one JSON line on stdout

imitation is set up as its documentation recommends for synthetic preferences: a bagged
ensemble of `BasicRewardNet`s (running input normalisation) trained by its ensemble
trainer, active selection of the most disputed fragment pairs, PPO on the ensemble mean
through `NormalizedRewardNet` (running centring and scaling of the reward), a Boltzmann
`SyntheticGatherer`. Budgets, PPO settings and the query schedule come from the spec, so
they are the same as groupwise's cell.
"""

import json
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from imitation.algorithms import preference_comparisons as pc
from imitation.rewards.reward_nets import BasicRewardNet, NormalizedRewardNet, RewardEnsemble
from imitation.util import networks
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

from peer_eval import episode_returns


def make_env_factory(spec: dict):
    env_id = spec["env"]
    if spec.get("groupwise_env"):
        # groupwise's own envs: import their module from the checkout (registers them)
        sys.path.insert(0, str(Path(spec["src"])))
        module, _, name = spec["groupwise_env"].partition(":")
        cls = getattr(__import__(module, fromlist=[name]), name)
        if env_id not in gym.registry:  # importing groupwise.envs registers them already
            gym.register(env_id, entry_point=cls, max_episode_steps=spec["horizon"])
    return lambda: gym.make(env_id, **spec.get("env_kwargs", {}))


def evaluate(model: PPO, norm: VecNormalize, make, seeds: list[int]) -> list[float]:
    def act(obs: np.ndarray) -> np.ndarray:
        return model.predict(norm.normalize_obs(obs), deterministic=True)[0]

    return episode_returns(act, make, seeds)


def main(spec: dict) -> dict:
    started = time.perf_counter()
    torch.set_num_threads(1)
    seed = spec["seed"]
    rng = np.random.default_rng(seed)
    torch.manual_seed(seed)
    make = make_env_factory(spec)
    ppo_cfg = spec["ppo"]
    venv = VecNormalize(
        DummyVecEnv([make] * ppo_cfg["n_envs"]),
        norm_obs=True,
        norm_reward=False,
        gamma=ppo_cfg["gamma"],
    )
    venv.seed(seed)
    members = [
        BasicRewardNet(
            venv.observation_space,
            venv.action_space,
            hid_sizes=tuple(spec["reward_hidden"]),
            normalize_input_layer=networks.RunningNorm,
        )
        for _ in range(spec["ensemble_size"])
    ]
    ensemble = RewardEnsemble(venv.observation_space, venv.action_space, members)
    reward_fn = NormalizedRewardNet(ensemble, normalize_output_layer=networks.RunningNorm)
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=ppo_cfg["n_steps"],
        batch_size=ppo_cfg["batch_size"],
        n_epochs=ppo_cfg["n_epochs"],
        learning_rate=ppo_cfg["learning_rate"],
        clip_range=ppo_cfg["clip_range"],
        gamma=ppo_cfg["gamma"],
        gae_lambda=ppo_cfg["gae_lambda"],
        ent_coef=ppo_cfg["ent_coef"],
        policy_kwargs={"net_arch": list(ppo_cfg["net_arch"])},
        seed=seed,
        device="cpu",
        verbose=0,
    )
    ppo_seconds = [0.0]
    trainer = pc.AgentTrainer(
        model, reward_fn, venv, rng=rng, exploration_frac=spec["exploration_fraction"]
    )
    learn = trainer.train

    def timed_learn(steps: int, **kwargs) -> None:
        tick = time.perf_counter()
        learn(steps, **kwargs)
        ppo_seconds[0] += time.perf_counter() - tick

    trainer.train = timed_learn  # type: ignore[method-assign]  # timed in place
    preference_model = pc.PreferenceModel(ensemble)
    fragmenter = pc.ActiveSelectionFragmenter(
        preference_model,
        pc.RandomFragmenter(rng=rng, warning_threshold=0),
        fragment_sample_factor=spec["candidate_pairs"],
        uncertainty_on="logit",
    )
    gatherer = pc.SyntheticGatherer(
        temperature=spec["boltzmann_beta"], discount_factor=1, sample=True, rng=rng
    )
    # imitation's ensemble trainer (bagging), 3 epochs a round as in its tutorial
    reward_trainer = pc._make_reward_trainer(
        preference_model, pc.CrossEntropyRewardLoss(), rng, reward_trainer_kwargs={"epochs": 3}
    )
    algorithm = pc.PreferenceComparisons(
        trainer,
        ensemble,
        num_iterations=spec["rounds"] - 1,  # imitation asks round 0 + num_iterations rounds
        fragmenter=fragmenter,
        preference_gatherer=gatherer,
        reward_trainer=reward_trainer,
        fragment_length=spec["fragment_length"],
        transition_oversampling=1,
        initial_comparison_frac=spec["initial_fraction"],
        # imitation's default 200; 10 (ours) with SPEC noise (peer.noise_spec)
        initial_epoch_multiplier=spec.get("imitation_initial_epoch_multiplier", 200.0),
        allow_variable_horizon=False,
        query_schedule="constant",
    )
    curve: list[float] = []
    seeds = spec["eval_seeds"]
    algorithm.train(
        total_timesteps=spec["steps_per_round"] * (spec["rounds"] - 1),
        total_comparisons=spec["comparisons"],
        callback=lambda _: curve.append(float(np.mean(evaluate(model, venv, make, seeds)))),
    )
    final = evaluate(model, venv, make, seeds)
    wall = time.perf_counter() - started
    return {
        "side": "imitation",
        "env": spec["env"],
        "seed": seed,
        "variant": "imitation",
        "wall_s": wall,
        "ppo_s": ppo_seconds[0],
        "non_ppo_s": wall - ppo_seconds[0],
        "final_return": float(np.mean(final)),
        "curve": curve,
        "env_steps": int(model.num_timesteps),
    }


if __name__ == "__main__":
    import contextlib
    import io

    with contextlib.redirect_stdout(io.StringIO()):  # imitation prints its query schedule
        result = main(json.loads(sys.argv[1]))
    print(json.dumps(result))
