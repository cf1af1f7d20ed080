"""Monte Carlo attack sweeps: specs (grid / random), the result store (content-hashed ids,
resume), executors (a local spawn pool or Ray) and the report."""
