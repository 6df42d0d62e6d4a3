"""Training PPO agents (stable-baselines3, the ``train`` extra): the trainer
(:mod:`~cstep_bridge.training.trainer`) and its protocols, curriculum, noise cap, normalisation,
model selection, batched rewards and logs, the export of a finished run, and campaigns of runs on
this machine or on Ray (:mod:`~cstep_bridge.training.campaign`,
:mod:`~cstep_bridge.training.ray_backend`)."""
