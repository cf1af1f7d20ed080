"""The supervisor (runtime assurance, issue 69): a car stage above any defence.

It runs the following stage as its advanced controller and vouches, each step, for the distance
that stage defends (:mod:`.vouch`: witnesses that agree, a track with no break, motion a car can
make). While it cannot, a safe controller drives on the worst case the target's last vouched place
allows (:mod:`.track`), with the stated envelope's arithmetic (:mod:`.envelope`: RSS's safe
distance); a target tracked in the lane stays there until the LiDAR sees the lane clear
(:mod:`.clear`), and one first seen too near needs a range witness before it may brake the car hard
(:mod:`.appearance`). The guarantee and its proof: ``docs/concepts/guarantee.md``.
"""
