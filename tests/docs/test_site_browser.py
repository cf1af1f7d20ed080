"""The built site as a reader's browser shows it: headless Chromium (Debian's, driven by Playwright;
nothing downloaded) opens every page from ``file://`` at 1280 px and finds a clean console, no
horizontal scroll, every internal link and image there; the leaderboard sorts, and its boards fit.
Screenshots of the leaderboard, a card and the moment are kept in ``outputs/browser/``.

Slow (the site's build and ~80 pages): CI's slow stage runs it; ``make browser`` installs Chromium."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from urllib.parse import unquote, urlparse

import pytest

ROOT = Path(__file__).resolve().parents[2]
SHOTS = ROOT / "outputs" / "browser"
WIDTH = 1280
#: Chromium as the machine's package installs it; the flags keep it from calling home (the network is closed).
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--disable-quic"]

pytestmark = pytest.mark.slow


def chromium() -> str:
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found is None:
        pytest.fail("no Chromium: `make browser` installs Debian's (apt-get install chromium)")
    return found


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run([str(Path(sys.executable).parent / "mkdocs"), "build", "--strict", "--site-dir", str(out)],
                          cwd=ROOT, capture_output=True, text=True, env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert done.returncode == 0, done.stderr[-3000:]
    return out


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium(), args=CHROMIUM_ARGS)
        yield b
        b.close()


def open_page(browser, url: str, width: int = WIDTH):
    page = browser.new_page(viewport={"width": width, "height": 900})
    problems: list[str] = []
    page.on("console", lambda m: problems.append(f"console {m.type}: {m.text}") if m.type in ("error", "warning") else None)
    page.on("pageerror", lambda e: problems.append(f"script error: {e}"))
    page.on("requestfailed", lambda r: problems.append(f"request failed: {r.url} ({r.failure})"))
    page.goto(url, wait_until="load")
    return page, problems


def pages(site: Path) -> list[Path]:
    return sorted(p for p in site.rglob("*.html") if p.name != "404.html")


def test_every_page_loads_clean_fits_1280_px_and_its_links_and_images_resolve(site, browser):
    faults = []
    for path in pages(site):
        page, problems = open_page(browser, path.as_uri())
        name = str(path.relative_to(site))
        overflow = page.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth")
        if overflow > 0:
            problems.append(f"{overflow} px of horizontal scroll at {WIDTH} px")
        # Nor a table that scrolls sideways in its own box (the theme wraps each in one).
        wide = page.evaluate("Array.from(document.querySelectorAll('.md-typeset__scrollwrap, .racf-board-wrap, "
                             ".racf-heatmap-wrap')).map(e => e.scrollWidth - e.clientWidth).filter(d => d > 1)")
        problems += [f"a table {d} px wider than its column at {WIDTH} px" for d in wide]
        broken = page.evaluate("Array.from(document.images).filter(i => !i.complete || i.naturalWidth === 0)"
                               ".map(i => i.getAttribute('src'))")
        problems += [f"image does not load: {src}" for src in broken]
        for href in page.evaluate("Array.from(document.querySelectorAll('a[href]')).map(a => a.href)"):
            url = urlparse(href)
            if url.scheme == "file" and not Path(unquote(url.path)).exists():
                problems.append(f"link to nothing: {href}")
        faults += [f"{name}: {p}" for p in problems]
        page.close()
    assert faults == [], "\n".join(faults[:40])


def test_the_leaderboard_sorts_and_its_boards_fit_1280_px(site, browser):
    import json

    page, problems = open_page(browser, (site / "results" / "leaderboard.html").as_uri())
    # racf-5's and racf-4's boards and heatmaps: nothing to scroll sideways inside them either.
    for battery in ("racf-5", "racf-4"):
        heading = page.locator(f"h2:has(code:text-is('{battery}'))")
        assert heading.count() == 1, battery
        for wrap in ("racf-board-wrap", "racf-heatmap-wrap"):
            box = heading.locator(f"xpath=following::div[contains(@class, '{wrap}')][1]")
            assert box.evaluate("e => e.scrollWidth - e.clientWidth") <= 0, (battery, wrap)
        # The heatmap shows every defence and every row the stored cards have.
        cards = json.loads((ROOT / "docs/results/data" / f"scorecard-{battery}.json").read_text())["cards"]
        submitted = [json.loads(p.read_text())["card"]["defence"]
                     for p in sorted((ROOT / "docs/results/submissions").glob(f"{battery}-*.json"))]
        heat = heading.locator("xpath=following::table[contains(@class, 'racf-heatmap')][1]")
        shown = heat.locator("thead th code").all_inner_texts()
        assert shown == [c["defence"] for c in cards] + submitted
        assert heat.locator("td.racf-row").count() == len(cards[0]["closed_loop"])
    board = page.locator("table.racf-sortable").first
    head = board.locator("th", has_text="attacked rows, pooled")
    column = board.locator("th").all_inner_texts().index(head.inner_text())

    def values():
        cells = board.locator(f"tbody tr td:nth-child({column + 1})")
        return [float(v) if v else -1.0 for v in (cells.nth(i).get_attribute("data-sort")
                                                    for i in range(cells.count()))]

    head.click()
    assert values() == sorted(values(), reverse=True) and head.get_attribute("aria-sort") == "descending"
    head.click()
    assert values() == sorted(values()) and head.get_attribute("aria-sort") == "ascending"
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / "leaderboard.png"))
    assert problems == []


def test_each_board_names_its_measures_marks_one_best_per_column_and_has_a_driving_score_or_says_why(site, browser):
    page, problems = open_page(browser, (site / "results" / "leaderboard.html").as_uri())
    boards = page.locator("table.racf-board")
    assert boards.count() >= 6
    for b in range(boards.count()):
        board = boards.nth(b)
        heads = board.locator("thead th")
        names = heads.all_inner_texts()
        for i in range(1, heads.count()):  # every head but the defence's names its measure and its direction
            assert heads.nth(i).locator("small.racf-measure").count() == 1, names[i]
            assert "is better" in heads.nth(i).inner_text(), names[i]
            column = board.locator(f"tbody tr td:nth-child({i + 1})")
            valued = [v for v in (column.nth(r).get_attribute("data-sort") for r in range(column.count())) if v]
            best = board.locator(f"tbody tr td:nth-child({i + 1}).racf-best")
            assert best.count() == (1 if len(valued) > 1 else 0), names[i]
        heading = board.locator("xpath=preceding::h2[1]").inner_text()
        said_why = board.locator("xpath=following::p[1]").inner_text().startswith("No driving score")
        assert any(n.startswith("driving score") for n in names) != said_why, heading
    assert problems == []


def test_a_card_shows_its_headline_in_the_first_screen(site, browser):
    page, problems = open_page(browser, (site / "results" / "cards" / "racf-5-vote.html").as_uri())
    top = page.locator("table.racf-headline").bounding_box()
    assert top is not None and top["y"] + 60 < 900  # its first rows are on the first screen
    page.screenshot(path=str(SHOTS / "card.png"))
    assert problems == []


def test_a_phone_reads_the_leaderboard_without_scrolling_the_page_sideways(site, browser):
    page, problems = open_page(browser, (site / "results" / "leaderboard.html").as_uri(), width=390)
    assert page.evaluate("document.documentElement.scrollWidth - document.documentElement.clientWidth") <= 0
    assert problems == []


def test_the_recording_page_shows_the_moment(site, browser):
    page, problems = open_page(browser, (site / "getting-started.html").as_uri())
    picture = page.locator("img[src$='moment.png']")
    assert picture.count() == 1 and picture.evaluate("i => i.complete && i.naturalWidth > 1000")
    SHOTS.mkdir(parents=True, exist_ok=True)
    picture.screenshot(path=str(SHOTS / "moment.png"))
    assert problems == []
