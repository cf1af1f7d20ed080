"""``racf board check`` and ``racf board submit``: a card's way onto the leaderboard
(``racf.experiments.scorecard.submission`` says what a submission holds)."""

from __future__ import annotations

import argparse
from pathlib import Path

from racf.experiments.cli.common import fail

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    c = sub.add_parser("board-check", help="whether cards may go on the leaderboard: full battery, full N, "
                                           "measured on a committed tree",
                       description="Checks each card (a file `racf scorecard --json` wrote, or one under "
                                   "OUT/cards/): its battery is racf's and not the quick one, every row is there at "
                                   "the battery's N, its version names the code and its commit has no uncommitted "
                                   "changes. Prints one line per card; exit 2 if any may not go on the board.")
    c.add_argument("cards", type=Path, nargs="+", metavar="CARD.json")
    c.set_defaults(handler=_check)
    s = sub.add_parser("board-submit", help="put a checked card beside racf's own: writes its submission file",
                       description="Checks the card (as `racf board check`), then writes "
                                   "docs/results/submissions/<battery>-<defence>.json with the card, where its "
                                   "code is and the command that measured it. `make docs` then shows it on the "
                                   "leaderboard with a page of its own; open a pull request with the file.")
    s.add_argument("card", type=Path, metavar="CARD.json")
    s.add_argument("--code", required=True, metavar="WHERE",
                   help="where the defence's code is: a package (racf-cusum==0.1.0), a repository at a commit, "
                        "or a path in racf's tree")
    s.add_argument("--command", dest="measured_by", required=True, metavar="COMMAND",
                   help="the `racf scorecard ...` command that measured it")
    s.add_argument("--into", type=Path, default=None, metavar="DIR",
                   help="the submissions folder (default docs/results/submissions of this checkout)")
    s.set_defaults(handler=_submit)


def _check(args: argparse.Namespace) -> int:
    from racf.experiments.scorecard.submission import card_problems, load_card

    bad = []
    for path in args.cards:
        card = load_card(path)
        problems = card_problems(card)
        name = f"{path}: {card['defence']} on {card['battery']}"
        print(f"{name}: may go on the board" if not problems else f"{name}: not yet: {'; '.join(problems)}")
        bad += [path] if problems else []
    if bad:
        fail("board check", f"{len(bad)} of {len(args.cards)} card(s) may not go on the board (each line above "
                            "says why)")
    return 0


def _submit(args: argparse.Namespace) -> int:
    from racf.experiments.scorecard.submission import SUBMISSIONS, Submission, load_card, load_submissions
    from racf.provenance import atomic_write

    folder = args.into or SUBMISSIONS
    card = load_card(args.card)
    taken = _board_defences(card["battery"]) - {s.card["defence"] for s in load_submissions(folder)
                                                if s.card["battery"] == card["battery"]}
    submission = Submission.make(card, args.code, args.measured_by, taken)
    Path(folder).mkdir(parents=True, exist_ok=True)
    path = atomic_write(Path(folder) / submission.file_name, submission.to_json())
    print(f"wrote {path}; `make docs` sets it on the leaderboard beside racf's own cards; open a pull request "
          "with that file to submit it")
    return 0


def _board_defences(battery: str) -> set[str]:
    """The defences racf's own stored cards name on ``battery``, from every stored scorecard that holds
    some (a submission may not take their names)."""
    import json

    return {card["defence"] for path in Path("docs/results/data").glob("scorecard-*.json")
            for card in json.loads(path.read_text()).get("cards", []) if card["battery"] == battery}
