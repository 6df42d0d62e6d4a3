"""The rewards: the task's ``exp(−d)`` (:mod:`~cstep_bridge.reward.task`), what a collision is
worth to an empowered agent (:mod:`~cstep_bridge.reward.collision`) and C-STEP scored in this
process by the node's own scoring step (:mod:`~cstep_bridge.reward.scoring`)."""
