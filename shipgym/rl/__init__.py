"""Reinforcement learning for shipgym: training and benchmarking learned controllers.

- :mod:`~shipgym.rl.train`: ``shipgym train ppo|sac`` (hyperparameters in
  ``shipgym/rl/hyperparams/*.yml``, rl-zoo3's layout), vectorised training envs, periodic
  evaluation (harbour manoeuvre or station keeping), checkpoints, resuming, TensorBoard,
  deterministic settings;
- :mod:`~shipgym.rl.evaluation`: closed-loop episodes of any named controller;
- :mod:`~shipgym.rl.bench`: ``shipgym bench controllers`` (pid vs lq vs learned).

The learned controllers themselves (model format, loading, the wrapper) live in
:mod:`shipgym.controllers.learned`. Needs the ``rl`` extra (torch, stable-baselines3).
"""

__all__ = ["bench", "evaluation", "train"]
