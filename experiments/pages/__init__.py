"""The results pages of the docs (``docs/results/``), written from the stored results in
``docs/results/data/``: the store that keeps a measured result with its provenance
(:mod:`~racf.experiments.pages.results_store`), and one writer per page. The top of the
experiments: pages read sweeps, scorecards and falsification reports; nothing reads pages."""
