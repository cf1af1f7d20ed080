"""The offline repair benchmark: methods behind one interface, metrics, scoring, the benchmark and its report."""
