"""Runtime assurance (Simplex) above the car's defences, at every target it publishes a track of.

A stage publishes what it believes of its target as a typed track
(:class:`~racf.experiments.car.stage.TargetTrack`); a supervisor reads only that. For a moving target
(:mod:`.vehicle`) it vouches, each step, for a range reading (:mod:`.vouch`: witnesses that agree, a
track with no break, motion the target can make, a refusal judged again), carries the target at the
worst case its last vouched place allows (:mod:`.track`, with the target's speed measured by the car
itself, :mod:`.speed`), never drives bolder than the defence without positive evidence, and tells the
car to stop once it is faster than the worst-case gap allows (:mod:`.envelope`: RSS's safe distance); a
target in the lane stays there until the LiDAR sees the lane clear (:mod:`.clear`). For a static target
(:mod:`.static`: the stop sign, a person) it vouches for the target's place with the car's own
witnesses, outvotes a defended or served distance that lies beyond it, and holds the car to stop before
its line. The guarantee and its proof: ``docs/concepts/guarantee.md``.
"""
