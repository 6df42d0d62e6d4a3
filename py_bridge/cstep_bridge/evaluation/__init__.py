"""Evaluating trained agents (the ``train`` extra): the evaluation set, flying models over it
(:mod:`~cstep_bridge.evaluation.flights`) by an acting rule, the paper's metrics, confidence
intervals and paired tests, the cache of flown episodes, the figures, and the command that tables
them (:mod:`~cstep_bridge.evaluation.evaluate`)."""
