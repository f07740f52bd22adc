"""Several people teach one agent (issue 21; docs/app.md, "Shared sessions"): the owner adds
an annotator and hands them their link; two pages, each in a browser profile of its own, on
one server. A comparison made on one page reaches the other's counters and history through
the event stream; the annotator cannot undo the owner's comparison and is told why; the two
pages are offered different suggestions, and a suggestion answered on one page leaves the
other. Screenshots: annotators-owner.png, annotators-annotator.png, annotators-dialog.png,
annotators-refusal.png (1366 × 768)."""

import re
import time
from typing import Any

import pytest

expect = pytest.importorskip("playwright.sync_api").expect
Page = Any  # playwright.sync_api.Page
Server = Any  # conftest.Server

POOL = 16
A_BETTER = "Group A (left) is better"


def _open(page: Page, url: str) -> None:
    page.goto(url)
    expect(page.locator(".arc.leaf")).to_have_count(POOL)
    expect(page.locator(".comparison .origin")).to_have_text(
        "Suggested comparison · 0 edits", timeout=15_000
    )
    # The server renders a clip on its first request (clips/on_demand.py: the first ones wait
    # for its render processes to start) and a browser keeps 6 connections to it: until the
    # groups' clips have arrived, the page's own requests queue behind them.
    page.wait_for_function(
        """() => [...document.querySelectorAll('.group video')]
            .every((v) => v.readyState >= 2 || v.error)""",
        timeout=120_000,
    )


def _add_annotator(page: Page, name: str, shot: Any) -> str:
    """Adds `name` in the owner's Annotators dialog; their link, as the dialog shows it."""
    page.get_by_role("button", name="Annotators").click()
    dialog = page.get_by_role("dialog", name="Annotators")
    expect(dialog).to_be_visible()
    dialog.get_by_label("Name of the person to add").fill(name)
    dialog.get_by_role("button", name="Add", exact=True).click()
    link = dialog.get_by_label(re.compile(f"^{name}'s link"))
    expect(link).to_have_value(re.compile(r"^http://127\.0\.0\.1:\d+/\?session=s-.+&token=.+"))
    expect(dialog.get_by_role("listitem").filter(has_text=name)).to_be_visible()
    shot(page, "annotators-dialog")
    value = str(link.input_value())
    page.keyboard.press("Escape")
    expect(dialog).to_be_hidden()
    return value


def _row(page: Page, who: str) -> Any:
    """A person's row in the page's Annotators panel."""
    return page.get_by_role("region", name="Annotators").locator(f'tr[data-id="{who}"]')


def _groups(page: Page) -> tuple[list[str], list[str]]:
    ids = "els => els.map(e => e.dataset.id).sort()"
    a = page.eval_on_selector_all(".group-A .clip", ids)
    b = page.eval_on_selector_all(".group-B .clip", ids)
    return list(a), list(b)


def test_two_people_teach_one_agent(
    server: Server, page: Page, other_page: Page, shot: Any
) -> None:
    sid = server.new_session("groupwise")
    owner, ann = page, other_page
    _open(owner, f"{server.url}/?session={sid}")
    # a session nobody shares: no names, no people panel; the owner can share it
    expect(owner.locator(".statusbar .who")).to_be_hidden()
    expect(owner.get_by_role("region", name="Annotators")).to_be_hidden()

    link = _add_annotator(owner, "Ann", shot)
    people = server.api("GET", f"/api/sessions/{sid}/annotators")
    [person] = [p for p in people if p["id"] != "owner"]
    assert person["name"] == "Ann"
    # shared now: the owner's name on the control, and everyone in the panel
    control = owner.get_by_role("button", name="Annotators · you are owner, the owner")
    expect(control).to_be_visible()
    expect(_row(owner, person["id"])).to_contain_text("Ann")

    _open(ann, link)
    expect(ann.locator(".statusbar .who .who-name")).to_have_text("Ann")
    for name in ("End round", "Finish now", "Pause", "Annotators"):
        expect(ann.get_by_role("button", name=name)).to_have_count(0)
    expect(_row(ann, person["id"])).to_contain_text("Ann (you)")
    # each page was offered a suggestion of its own (the server leases one per person)
    owner_groups, ann_groups = _groups(owner), _groups(ann)
    assert owner_groups[0] and ann_groups[0]
    assert owner_groups != ann_groups, (owner_groups, ann_groups)

    # the owner answers: the annotator's counters, history and chart follow from the stream
    owner.get_by_role("button", name=A_BETTER).click()
    expect(owner.locator(".toast")).to_contain_text("Saved")
    tick = time.monotonic()
    [stored] = server.judgements(sid, 0)
    assert stored["annotator"] == {"id": "owner", "name": "owner"}
    expect(_row(ann, "owner").locator(".comparisons")).to_have_text("1")
    print(f"owner's answer → annotator's counters: {time.monotonic() - tick:.2f} s")
    expect(_row(ann, "owner").locator(".pairs")).to_have_text(str(len(stored["pairs"])))
    history = ann.get_by_role("region", name="Annotators").locator(".history-row")
    expect(history).to_have_count(1)
    expect(history.first).to_have_attribute("data-annotator", "owner")
    said = re.compile(r"^owner: .* A better · \d+ pairs?")
    expect(history.first).to_have_attribute("title", said)
    edges = len({(p["a"], p["b"]) for p in stored["pairs"]})
    expect(ann.locator("canvas.chart-edges")).to_have_attribute("data-history", str(edges))
    expect(ann.locator(".statusbar")).to_contain_text("1 total")

    # the annotator cannot take the owner's answer back, and is told why
    ann.get_by_role("button", name="Undo last answer").click()
    refusal = ann.locator(".toast-error")
    expect(refusal).to_contain_text(re.compile(r"^Not undone: judgement .* only they can undo it"))
    expect(_row(ann, "owner").locator(".comparisons")).to_have_text("1")
    expect(history).to_have_count(1)
    assert [j["id"] for j in server.judgements(sid, 0)] == [stored["id"]]
    shot(ann, "annotators-refusal")

    # the annotator answers: the owner sees it, initials and all
    ann.get_by_role("button", name=A_BETTER).click()
    expect(ann.locator(".toast")).to_contain_text("Saved")
    expect(_row(owner, person["id"]).locator(".comparisons")).to_have_text("1")
    mine = owner.get_by_role("region", name="Annotators").locator(".history-row")
    expect(mine).to_have_count(2)
    expect(mine.first).to_have_attribute("data-annotator", person["id"])
    expect(mine.first.locator(".person-badge")).to_have_text("A")
    both = {(p["a"], p["b"]) for j in server.judgements(sid, 0) for p in j["pairs"]}
    expect(owner.locator("canvas.chart-edges")).to_have_attribute("data-history", str(len(both)))
    # their own answer is theirs to undo
    ann.get_by_role("button", name="Undo last answer").click()
    expect(ann.locator(".toast")).to_contain_text("Last answer undone.")
    expect(_row(owner, person["id"]).locator(".comparisons")).to_have_text("0")
    expect(mine).to_have_count(1)

    # Ann's page reported the round shown: her time shown grows (read again every 10 s)
    expect(_row(owner, person["id"]).locator(".shown")).not_to_have_text("0:00", timeout=15_000)
    for pg in (owner, ann):  # the bar keeps one line, the names on it
        bar = pg.locator(".statusbar")
        assert bar.evaluate("b => b.scrollWidth <= b.clientWidth && b.clientHeight < 60")
    shot(owner, "annotators-owner")
    shot(ann, "annotators-annotator")

    # removed: the link stops working, the judgements stay
    owner.get_by_role("button", name=re.compile("^Annotators")).click()
    dialog = owner.get_by_role("dialog", name="Annotators")
    dialog.get_by_role("button", name="Remove Ann").click()
    dialog.get_by_role("button", name="Click again to remove Ann").click()
    expect(dialog.get_by_role("listitem")).to_have_count(0)
    assert [p["id"] for p in server.api("GET", f"/api/sessions/{sid}/annotators")] == ["owner"]


def test_a_suggestion_answered_elsewhere_leaves_the_other_page(
    server: Server, page: Page, other_page: Page, shot: Any
) -> None:
    """Without leases both pages are offered the same suggestion: when one answers it, the
    other drops it and shows the next one (the judgement event names the suggestion)."""
    sid = server.new_session("groupwise", lease_s=0, overlap_share=0)
    owner, ann = page, other_page
    _open(owner, f"{server.url}/?session={sid}")
    link = _add_annotator(owner, "Ann", shot)
    _open(ann, link)
    shown = _groups(ann)
    assert _groups(owner) == shown  # no leases: the same first suggestion

    owner.get_by_role("button", name=A_BETTER).click()
    expect(owner.locator(".toast")).to_contain_text("Saved")
    expect(ann.locator(".toast")).to_have_text(
        re.compile("^owner answered the suggestion you had; here is the next one.")
    )
    ann.wait_for_function(
        """(shown) => {
            const ids = (g) => [...document.querySelectorAll(`.group-${g} .clip`)]
                .map((e) => e.dataset.id).sort();
            const now = [ids("A"), ids("B")];
            return now[0].length > 0 && JSON.stringify(now) !== JSON.stringify(shown);
        }""",
        arg=[shown[0], shown[1]],
    )
    expect(ann.locator(".comparison .origin")).to_have_text("Suggested comparison · 0 edits")
    # the annotator answers the next one: one judgement each, of different suggestions
    ann.get_by_role("button", name=A_BETTER).click()
    expect(ann.locator(".toast")).to_contain_text("Saved")
    judgements = server.judgements(sid, 0)
    assert [j["annotator"]["name"] for j in judgements] == ["owner", "Ann"]
    assert judgements[0]["suggestion_id"] != judgements[1]["suggestion_id"]
