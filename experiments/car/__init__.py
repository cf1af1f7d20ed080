"""The car's software, the second of the episode's three rooms (the engine, the car, the link).

Everything here reads the observation and the map, never ground truth: its assembly
(:mod:`.software`: localisation, perception, the braker, the lane follower), the stages a mission
engages (:mod:`.stage`: the contract; :mod:`.following`: the car ahead), and the defences racf
ships (:mod:`.estimators`: ODCA, Chronos; :mod:`.existence_defences`: the existence vote and its
baselines, with the witnesses :mod:`.existence` gathers). The engine
(:mod:`racf.experiments.episode`) wires these parts per spec; the link
(:mod:`racf.experiments.link`) reaches a defence served elsewhere.
"""
