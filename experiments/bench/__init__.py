"""Speed benchmarks: simulator, detector, ODCA latency."""
