"""``racf scorecard``: a defence (or an attack) rated on a named, versioned battery.

- :mod:`~racf.experiments.scorecard.battery`: the batteries, row by row;
- :mod:`~racf.experiments.scorecard.card`: one defence's card, run or resumed;
- :mod:`~racf.experiments.scorecard.detection`, :mod:`~racf.experiments.scorecard.drives`,
  :mod:`~racf.experiments.scorecard.offline`: the rows that are not plain SCRs;
- :mod:`~racf.experiments.scorecard.attack_card`: an attack against every defence;
- :mod:`~racf.experiments.scorecard.report`: the Markdown, JSON and HTML, and two cards compared.
"""
