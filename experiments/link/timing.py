"""How long the car waits for a served defence, in a module of its own: the command line's help
names the default without importing the wire (which imports the car's perception)."""

__all__ = ["DEFAULT_TIMEOUT_MS", "DEFAULT_RETRY_S"]

#: How long a car waits for an answer before it falls back, and how much of its own time then
#: passes before it asks again. Set from the measured round trip with a margin: 8 cars at 50 Hz
#: on 2 cores (``racf bench service-stress --cars 8 --seconds 120 --timeout-ms 2000``) had a
#: p99 of 9.2 ms, a p99.9 of 31 ms and a longest of 49 ms, and the p99 beside a sweep was about
#: 46 ms; 150 ms is three times the longest, so a loaded machine's tail is waited for. A car that
#: got no answer asks again 0.2 s later (10 steps), not 1 s (50 steps of its own depth).
DEFAULT_TIMEOUT_MS = 150.0
DEFAULT_RETRY_S = 0.2
