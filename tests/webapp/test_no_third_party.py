"""No page and no chart links to, loads from or sends data to a third-party service (issue 25,
item 5): patients' data stays on the clinic's site.

The demo's therapist, patient and clinic admin walk every page they can reach (the crawler of
`test_plain_words`), plus the API documentation page; every `href`, `src`, `action` and
`formaction` must stay on the site, and no page may name Plotly's cloud ("plot.ly", "chart-studio",
"plotly.com"). Charts take their options from one file, `webapp/static/js/chart_config.js`,
loaded right after plotly.js on every page that draws one; those options must switch off what
the bundled plotly.js version offers by default (its "Share chart..." button posting the chart's
data to Plotly's cloud, and the logo linking to plotly.com). The browser test
`tests/e2e/test_recording_recovery.py` checks the drawn mode bar.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import urlparse

import pytest
from django.conf import settings
from django.core.management import call_command

from tests.webapp.test_plain_words import USERS, crawl

URL_ATTRIBUTES = {"href", "src", "action", "formaction", "poster", "data", "srcset"}
CLOUD_WORDS = re.compile(r"plot\.ly|chart-studio|plotly\.com|cloud\.plotly", re.IGNORECASE)
PLOTLY = "vendor/plotly/plotly.min.js"
CHART_CONFIG = "js/chart_config.js"
STATIC_JS = Path(settings.BASE_DIR) / "webapp" / "static" / "js"


class Links(HTMLParser):
    """Every URL-valued attribute of a page, and the order of its scripts."""

    def __init__(self) -> None:
        super().__init__()
        self.urls: list[str] = []
        self.scripts: list[str] = []

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name in URL_ATTRIBUTES and value:
                self.urls += [part.split()[0] for part in value.split(",") if part.strip()]
        if tag == "script":
            self.scripts.append(dict(attrs).get("src") or "inline")


def third_party(markup: str) -> list[str]:
    """What in one page's markup leaves the site: URLs to other hosts, Plotly's cloud named."""
    links = Links()
    links.feed(markup)
    found = []
    for url in links.urls:
        parts = urlparse(url)
        elsewhere = parts.netloc not in ("", "testserver")  # "//host/..." included
        if elsewhere or parts.scheme not in ("", "http", "https", "mailto", "data", "blob"):
            found.append(url)
    found += CLOUD_WORDS.findall(markup)
    return found


def charts_configured(markup: str) -> bool | None:
    """None for a page without plotly.js; else whether the chart options follow it at once."""
    links = Links()
    links.feed(markup)
    scripts = links.scripts
    at = [i for i, src in enumerate(scripts) if src.endswith(PLOTLY)]
    if not at:
        return None
    return all(i + 1 < len(scripts) and scripts[i + 1].endswith(CHART_CONFIG) for i in at)


@pytest.mark.django_db
def test_no_page_links_to_a_third_party(client, settings):
    settings.DEMO_ALLOWED = True  # the demo loader refuses otherwise (published passwords)
    call_command("load_demo")
    problems: dict[str, list[str]] = {}
    with_charts = set()
    for username in USERS:
        assert client.login(username=username, password=f"{username}-pw")
        pages: dict[str, str] = {}
        crawl(client, pages)
        pages["/api/docs/"] = client.get("/api/docs/").content.decode()
        # Swagger UI's badge would send the schema's address to its online validator.
        assert '"validatorUrl": null' in pages["/api/docs/"]
        for path, markup in pages.items():
            if found := third_party(markup):
                problems[f"{username} {path}"] = sorted(set(found))
            configured = charts_configured(markup)
            if configured is False:
                problems[f"{username} {path}"] = ["plotly.js without chart_config.js after it"]
            if configured:
                with_charts.add(path.split("/")[1])
        client.logout()
    assert not problems, problems
    # The walk reached the pages that draw charts: recordings, progress, exercises' reports.
    assert {"recordings", "patients", "exercises"} <= with_charts, with_charts


def test_the_checker_finds_third_party_links():
    page = (
        '<a href="/patients/">ok</a><img src="https://cdn.example.org/x.png">'
        '<form action="//evil.example/steal"></form><a href="javascript:alert(1)">x</a>'
        '<script>Plotly.newPlot(d, t, l, {plotlyServerURL: "https://chart-studio.plotly.com"})'
        "</script>"
    )
    found = third_party(page)
    assert "https://cdn.example.org/x.png" in found and "//evil.example/steal" in found
    assert "javascript:alert(1)" in found and "chart-studio" in found
    assert third_party('<a href="http://testserver/help/">help</a><a href="#top">top</a>') == []
    scripts = f'<script src="/static/{PLOTLY}"></script><script src="/static/{CHART_CONFIG}">'
    assert charts_configured(scripts) is True
    assert charts_configured(f'<script src="/static/{PLOTLY}"></script>') is False
    assert charts_configured("<p>no chart</p>") is None


def chart_options() -> dict[str, str]:
    text = (STATIC_JS / "chart_config.js").read_text()
    body = text[text.index("const base = {") : text.index("};")]
    return dict(re.findall(r"(\w+): ([^,\n]+),", body))


def test_the_chart_options_switch_off_what_this_plotly_offers_by_default():
    """Each option is one the bundled plotly.js knows (a renamed key would silently do nothing),
    and each cloud feature it has on by default is switched off."""
    plotly = (
        Path(__import__("plotly").__file__).parent / "package_data" / "plotly.min.js"
    ).read_text()
    options = chart_options()
    for key in options:
        assert re.search(rf"\b{key}:\{{valType:", plotly), f"plotly.js has no config key {key}"
    defaults_on = {
        key
        for key in (
            "displaylogo",
            "showSendToCloud",
            "showEditInChartStudio",
            "showLink",
            "sendData",
        )
        if re.search(rf"\b{key}:\{{valType:\"boolean\",dflt:!0", plotly)
    }
    assert {"displaylogo", "showSendToCloud"} <= defaults_on  # what plotly.js 4 shows by default
    assert all(options.get(key) == "false" for key in defaults_on), options
    assert options["plotlyServerURL"] == '""'
    assert "sendChartToCloud" in options["modeBarButtonsToRemove"]


def test_every_chart_of_the_site_uses_the_shared_options():
    drawing = {
        path.name: path.read_text()
        for path in STATIC_JS.glob("*.js")
        if re.search(r"Plotly\.(newPlot|react|plot)\(", path.read_text())
    }
    assert {
        "recording_page.js",
        "progress.js",
        "clinical_progress.js",
        "training_report.js",
    } <= set(drawing)
    for name, text in drawing.items():
        assert "window.chartConfig(" in text, name
        assert "displaylogo" not in text, f"{name} sets chart options of its own"
        calls = re.findall(r"Plotly\.(?:newPlot|react)\(([^;]*)\);", text)
        assert calls and all(re.search(r"chartConfig\(\)|\bconfig\)?$", c) for c in calls), name
