"""``racf board check``, ``racf board verify`` and ``racf board submit``: a card's way onto the
leaderboard (``racf.experiments.scorecard.submission`` says what a submission holds,
``racf.experiments.scorecard.verify`` how a card is measured again)."""

from __future__ import annotations

import argparse
from pathlib import Path

from racf.experiments.cli.common import at_least, backend_flags, fail, plugin_flag

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
    v = sub.add_parser("board-verify", help="measure a card again: its summaries from its episodes, a sample of "
                                            "episodes re-run to the bit",
                       description="Verifies a card row by row: the code must be this checkout's, each row's "
                                   "episodes the battery's and its numbers what those episodes give, and a sample "
                                   "of each row's episodes, run again, must give the card's records and step logs "
                                   "to the bit. Prints one line per row with its time; exit 2 naming each row that "
                                   "fails. The sample is drawn afresh each run (--seed repeats one).")
    v.add_argument("card", type=Path, metavar="CARD.json")
    _verify_flags(v)
    v.set_defaults(handler=_verify)
    s = sub.add_parser("board-submit", help="put a verified card beside racf's own: writes its submission file",
                       description="Verifies the card (as `racf board verify`), then writes "
                                   "<battery>-<defence>.json into --into with the card, where its code is, the "
                                   "command that measured it and how it was verified. In racf's checkout that "
                                   "folder is docs/results/submissions: `make docs` then shows it on the "
                                   "leaderboard with a page of its own; open a pull request with the file.")
    s.add_argument("card", type=Path, metavar="CARD.json")
    s.add_argument("--code", required=True, metavar="WHERE",
                   help="where the defence's code is: a package (racf-cusum==0.1.0), a repository at a commit, "
                        "or a path in racf's tree")
    s.add_argument("--command", dest="measured_by", required=True, metavar="COMMAND",
                   help="the `racf scorecard ...` command that measured it")
    s.add_argument("--into", type=Path, required=True, metavar="DIR",
                   help="the folder to write the submission into (racf's is docs/results/submissions)")
    _verify_flags(s)
    s.set_defaults(handler=_submit)


def _verify_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--sample", type=at_least(0), default=5, metavar="K",
                   help="episodes run again per row (default 5: 30 s for racf-5's 12 rows on 2 cores, a following "
                        "row's episodes about 4 s each; 0 checks the numbers against the carried episodes only)")
    p.add_argument("--seed", type=int, default=None, help="the sample's seed (default: a fresh one, printed)")
    backend_flags(p, workers_help="parallel episodes")
    plugin_flag(p)


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


def _verify(args: argparse.Namespace) -> int:
    from racf.experiments.scorecard.submission import load_card

    _verified(load_card(args.card), args)
    return 0


def _verified(card: dict, args: argparse.Namespace) -> dict:
    """Verifies ``card`` as the flags say, a line per row; fails naming the rows refused. Returns how it
    was verified (for the submission)."""
    import time

    from racf.experiments.scorecard.verify import verify_card

    def say(v) -> None:
        what = (f"{v.rerun} of {v.n} episodes re-run, identical to the bit" if v.rerun else v.note or
                f"numbers match its {v.n} episodes") if v.ok else "; ".join(v.problems)
        print(f"row {v.key} (N {v.n}): {'ok' if v.ok else 'REFUSED'}: {what}; {v.seconds:.1f} s", flush=True)

    t0 = time.perf_counter()
    verdicts, seed = verify_card(card, sample=args.sample, seed=args.seed, workers=args.workers,
                                 backend=args.backend, address=args.address, progress=say)
    wall = time.perf_counter() - t0
    refused = [v.key for v in verdicts if not v.ok]
    rerun = sum(v.rerun for v in verdicts)
    print(f"{card['defence']} on {card['battery']}: {len(verdicts) - len(refused)} of {len(verdicts)} rows verified, "
          f"{rerun} episodes re-run in {wall:.0f} s on {args.workers} worker(s) "
          f"({wall / max(len(verdicts), 1):.1f} s a row); sample seed {seed} (--seed {seed} repeats it)")
    if refused:
        fail(_name(args), f"the card is refused: row(s) {', '.join(refused)} (each line above says why)")
    return {"sample": args.sample, "seed": seed, "rows": len(verdicts), "episodes_rerun": rerun}


def _name(args: argparse.Namespace) -> str:
    return "board submit" if getattr(args, "measured_by", None) is not None else "board verify"


def _submit(args: argparse.Namespace) -> int:
    from racf.experiments.scorecard.submission import Submission, load_card, load_submissions
    from racf.provenance import atomic_write

    folder = args.into
    card = load_card(args.card)
    taken = _board_defences(card["battery"]) - {s.card["defence"] for s in load_submissions(folder)
                                                if s.card["battery"] == card["battery"]}
    Submission.make(card, args.code, args.measured_by, taken)  # the cheap checks first: nothing runs for a bad card
    submission = Submission.make(card, args.code, args.measured_by, taken, verified=_verified(card, args))
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
