"""The link to a served defence, the third of the episode's three rooms (the engine, the car, the link).

The car's client (:mod:`.remote`), the protocol's one check of what a service may answer
(:mod:`.wire`), the CurveZMQ keys (:mod:`.curve`) and the man in the middle that the link attacks
act through (:mod:`.relay`). The service itself (:mod:`racf.experiments.service`) speaks the same
:mod:`.wire`.
"""
