"""Tables and charts on a phone, in a real browser with the demo clinic (issue 38):

- every table of every page a patient opens, at a 360 px phone, sits in the sideways-scrolling
  box the staff's pages use (`.scroll-box`): a region labelled by visible text on the page and
  reachable from the keyboard, so a wide table scrolls instead of squeezing its columns;
- every chart legend on the staff's pages with legends (a recording's angles, a patient's
  progress), at a 390 px phone, covers neither axis title of its chart (the legends sit outside
  the plot, and on a phone they wrap onto several lines).

`tests/e2e/test_page_widths.py` lists the pages; this file reuses its lists and demo objects.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.e2e.conftest import log_in
from tests.e2e.test_page_widths import PATIENT, PHONE, STAFF_PHONE, demo_objects, path_of

pytestmark = pytest.mark.e2e
# Each table's way out of the page: what is missing for it to scroll on its own, labelled.
UNBOXED_TABLES = """() => [...document.querySelectorAll('main table')].map((table, i) => {
  const box = table.closest('.scroll-box');
  const where = `table ${i + 1} (${(table.querySelector('th') || table).innerText.trim()})`;
  if (!box) return `${where}: in no scroll box`;
  const labels = (box.getAttribute('aria-labelledby') || '').split(/\\s+/)
    .map(id => document.getElementById(id)).filter(l => l && l.innerText.trim());
  if (box.getAttribute('role') !== 'region' || !labels.length || box.tabIndex !== 0)
    return `${where}: its box has no region role, visible label or keyboard stop`;
  if (getComputedStyle(box).overflowX !== 'auto') return `${where}: its box does not scroll`;
  return '';
}).filter(Boolean)"""
# Every drawn chart's legend against its axis titles: the pairs whose boxes intersect.
LEGEND_OVER_TITLE = """() => {
  const hit = (a, b) => a.left < b.right && b.left < a.right
    && a.top < b.bottom && b.top < a.bottom;
  const found = [], seen = [];
  for (const chart of document.querySelectorAll('.js-plotly-plot')) {
    // the legend's background: what it shows (a legend taller than its room scrolls, and the
    // entries past its clip still count in the group's own box)
    const legend = chart.querySelector('.legend rect.bg');
    if (!legend || !chart.getBoundingClientRect().width) continue;
    const box = legend.getBoundingClientRect();
    seen.push(chart.id || chart.className);
    for (const title of chart.querySelectorAll('.g-xtitle, .g-ytitle')) {
      const text = title.textContent.trim();
      if (text && hit(box, title.getBoundingClientRect()))
        found.push(`${chart.id || chart.className}: legend over "${text}"`);
    }
  }
  return [found, seen];
}"""
# The staff's pages with charts that have a legend, and what says their charts are drawn.
CHART_PAGES = {
    "reports:progress": "#progress[data-ready='1']",
    "recordings:detail": "#viewer[data-ready='1']",
}


def test_every_patient_table_scrolls_in_a_labelled_box(browser, live_server, demo):
    objects = demo_objects()
    found: dict[str, list[str]] = {}
    tables_seen = 0
    for username in dict.fromkeys(PATIENT.values()):
        context = browser.new_context(viewport={"width": PHONE, "height": 900})
        page = context.new_page()
        page.set_default_timeout(60_000)
        try:
            if username:
                log_in(page, live_server.url, username)
            for name in (n for n, user in PATIENT.items() if user == username):
                path = path_of(name, objects)
                page.goto(live_server.url + path)
                page.wait_for_load_state("load")
                tables_seen += page.locator("main table").count()
                if unboxed := page.evaluate(UNBOXED_TABLES):
                    found[f"{username or 'visitor'} {path}"] = unboxed
        finally:
            context.close()
    assert tables_seen > 0, "the demo patient's pages show no table: nothing was checked"
    assert found == {}, "tables outside a labelled scroll box on a patient's page"


def test_chart_legends_leave_the_axis_titles_clear_at_390(browser, live_server, demo):
    objects = demo_objects()
    context = browser.new_context(viewport={"width": STAFF_PHONE, "height": 900})
    page = context.new_page()
    page.set_default_timeout(60_000)
    found: dict[str, list[str]] = {}
    try:
        log_in(page, live_server.url, "demo-therapist")
        for name, drawn in CHART_PAGES.items():
            path = path_of(name, objects)
            page.goto(live_server.url + path)
            page.wait_for_selector(drawn, state="attached")
            page.wait_for_timeout(300)  # a legend that wraps is laid out after its first draw
            overlaps, seen = page.evaluate(LEGEND_OVER_TITLE)
            if os.environ.get("E2E_SHOTS"):  # a folder: a picture of each chart
                for k, chart in enumerate(page.locator(".js-plotly-plot").all()):
                    shot = Path(os.environ["E2E_SHOTS"]) / f"{name.replace(':', '-')}-{k}.png"
                    chart.screenshot(path=shot)
            assert seen, f"{path}: no chart with a legend was drawn, nothing was checked"
            if overlaps:
                found[path] = overlaps
    finally:
        context.close()
    assert found == {}, "legends over axis titles at 390 px"
